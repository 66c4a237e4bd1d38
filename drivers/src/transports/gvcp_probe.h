#pragma once
// Liveness probe of a GigE Vision device on its control channel: one GVCP READREG of the
// bootstrap Version register (address 0x0000; GigE Vision 2.0, sec. 15 "GVCP", READREG_CMD
// 0x0080 / READREG_ACK 0x0081), sent from a socket of its own with a short timeout per try.
//
// Why: Aravis 0.8 only notices a vanished device through its heartbeat, which retries for 5 s
// after GVCP reads of 5 x 500 ms fail (about 6 s from the loss), and its GVCP timeouts are not
// settable through its API. A device that answers nothing to `tries` reads of `try_timeout`
// each is gone or hung; a real camera answers a register read in well under a millisecond.
// Reading is allowed to any host (only writes need the control privilege), and the Version
// register is not the control-channel-privilege register whose reads count as heartbeats, so
// the probe never keeps a controller's session alive.
//
// Threading: one probe per thread (its socket and request id are not shared).

#include <netinet/in.h>

#include <chrono>
#include <cstdint>
#include <string>

namespace nav::drivers {

class GvcpProbe {
 public:
  /// `device` is the device's GVCP address (port 3956). Throws std::system_error when no UDP
  /// socket can be made.
  GvcpProbe(const sockaddr_in& device, std::chrono::milliseconds try_timeout, int tries);
  ~GvcpProbe();
  GvcpProbe(const GvcpProbe&) = delete;
  GvcpProbe& operator=(const GvcpProbe&) = delete;

  /// True when the device acknowledged a read within the tries. `why` (if given) says what
  /// failed, e.g. "no READREG_ACK from 127.0.0.1:3956 in 3 x 200 ms".
  bool answers(std::string* why = nullptr);

 private:
  /// Sends one READREG and waits up to the try timeout for its acknowledge.
  bool try_once();

  sockaddr_in device_{};
  std::chrono::milliseconds try_timeout_;
  int tries_;
  int fd_ = -1;
  std::uint16_t request_id_ = 0;
};

}  // namespace nav::drivers
