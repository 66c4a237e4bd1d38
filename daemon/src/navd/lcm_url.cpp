#include "navd/lcm_url.h"

#include <spdlog/spdlog.h>

#include <lcm/lcm-cpp.hpp>
#include <stdexcept>

namespace nav::navd {
namespace {

constexpr const char* kMemq = "memq://";

std::string why(const std::string& url) {
  std::string text = "cannot open LCM at '" + url + "'";
  if (url.rfind("udpm://", 0) == 0) {
    text +=
        ": no multicast route on this host (LCM's message above); as root: `ip link set lo up "
        "&& ip route add 224.0.0.0/4 dev lo` lets tools on this machine subscribe (ttl=0)";
  }
  return text;
}

}  // namespace

bool lcm_url_opens(const std::string& url) {
  const lcm::LCM lcm(url);
  return lcm.good();
}

std::string usable_lcm_url(const std::string& url, bool fallback_to_memq) {
  if (lcm_url_opens(url)) return url;
  if (!fallback_to_memq) throw std::invalid_argument(why(url));
  spdlog::warn("navd: {}; publishing in-process only ({}) instead", why(url), kMemq);
  return kMemq;
}

}  // namespace nav::navd
