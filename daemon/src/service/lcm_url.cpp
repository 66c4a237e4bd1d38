#include "nav/daemon/service/lcm_url.h"

#include <spdlog/spdlog.h>

#include <lcm/lcm-cpp.hpp>
#include <stdexcept>

namespace nav::daemon::service {
namespace {

constexpr const char* kMemq = "memq://";

}  // namespace

std::string lcm_open_error(const std::string& url) {
  std::string text = "cannot open LCM at '" + url + "'";
  if (url.rfind("udpm://", 0) == 0) {
    text +=
        ": no multicast route on this host (LCM's message above); as root, for this machine "
        "only (ttl=0): `ip link set lo up && ip route add 224.0.0.0/4 dev lo`, or the route via "
        "the interface topside listens on";
  }
  return text;
}

bool lcm_url_opens(const std::string& url) {
  const lcm::LCM lcm(url);
  return lcm.good();
}

std::string usable_lcm_url(const std::string& url, bool fallback_to_memq) {
  if (lcm_url_opens(url)) return url;
  if (!fallback_to_memq) throw std::invalid_argument(lcm_open_error(url));
  spdlog::warn("{}; publishing in-process only ({}) instead", lcm_open_error(url), kMemq);
  return kMemq;
}

}  // namespace nav::daemon::service
