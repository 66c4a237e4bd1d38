// navlcm::registration_t -> core::Registration (filter/registration_message.h).
#include "nav/daemon/filter/registration_message.h"

namespace nav::daemon {

core::Registration registration_from_message(const navlcm::registration_t& r) {
  core::Registration out;
  out.frame_id_i = r.frame_id_i;
  out.frame_id_j = r.frame_id_j;
  out.success = r.success;
  for (int k = 0; k < 5; ++k) out.z(k) = r.measurement[k];
  for (int k = 0; k < 25; ++k) out.covariance(k / 5, k % 5) = r.covariance[k];
  out.overlap_fraction = r.overlap_fraction;
  out.is_outlier = r.is_outlier;
  out.available_us = r.utime;
  return out;
}

}  // namespace nav::daemon
