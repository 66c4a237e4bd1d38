#pragma once
// Whether LCM udpm multicast with ttl=0 loops back to this process: the navd tests that
// subscribe over real udpm skip with the reason when it does not (docs/platform.md).
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>

namespace nav::tool::test {

/// True if a message published on `probe_channel` comes back within ~0.5 s.
inline bool udpm_loops_back(lcm::LCM& lcm, const std::string& probe_channel) {
  bool received = false;
  struct Probe {
    bool* flag;
    void on(const lcm::ReceiveBuffer*, const std::string&) { *flag = true; }
  } probe{&received};
  auto* sub = lcm.subscribe(probe_channel, &Probe::on, &probe);
  const std::uint8_t byte = 1;
  lcm.publish(probe_channel, &byte, 1);
  for (int i = 0; i < 10 && !received; ++i) lcm.handleTimeout(50);
  lcm.unsubscribe(sub);
  return received;
}

}  // namespace nav::tool::test
