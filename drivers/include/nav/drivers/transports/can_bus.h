#pragma once
// CAN bus transport (Linux SocketCAN, Documentation/networking/can.rst): classic CAN 2.0A/B
// frames with kernel receive timestamps (SO_TIMESTAMPNS), identifier filters with the kernel's
// CAN_RAW_FILTER semantics, and counted error frames (CAN_RAW_ERR_FILTER).
//
// CanBus is the interface drivers use; SocketCanBus implements it on a raw PF_CAN socket
// (open_interface) or on one end of a socketpair(AF_UNIX, SOCK_SEQPACKET) that carries
// `struct can_frame` bytes (open_can_socketpair). Both go through the same receive code path
// (framing, filtering, timestamps), so it is tested on machines whose kernel has no CAN.
//
// Threading: one driver thread calls receive(); send() may be called from one other thread
// (the socket is full duplex). Both block for at most their timeout. set_filters() and stats()
// belong to the receiving thread.

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "nav/drivers/time/timestamps.h"
#include "nav/drivers/transports/io_status.h"

namespace nav::drivers {

struct CanFrame {
  uint32_t id = 0;        ///< 11-bit (standard) or 29-bit (extended) identifier, no flag bits
  bool extended = false;  ///< 29-bit identifier (CAN 2.0B)
  bool remote = false;    ///< remote transmission request (no data)
  uint8_t dlc = 0;        ///< data length 0..8
  std::array<uint8_t, 8> data{};
  HostTime received;  ///< host clocks right after the frame was read from the socket
  /// When the kernel received the frame (SO_TIMESTAMPNS, CLOCK_REALTIME, µs); nullopt when the
  /// socket delivered no timestamp. Closer to the bus than `received` under load.
  std::optional<int64_t> kernel_realtime_us;
};

/// Accept a frame when (frame id & mask) == (id & mask) and its format (standard/extended)
/// equals `extended` — the kernel's CAN_RAW_FILTER rule with CAN_EFF_FLAG in id and mask.
struct CanFilter {
  uint32_t id = 0;
  uint32_t mask = 0;
  bool extended = false;
};

struct CanBusStats {
  uint64_t frames_received = 0;  ///< data/remote frames returned by receive()
  uint64_t frames_sent = 0;
  uint64_t filtered_out = 0;      ///< frames that did not pass the filters (user-space check)
  uint64_t error_frames = 0;      ///< CAN_ERR_FLAG frames (bus-off, error passive, ...)
  uint32_t last_error_class = 0;  ///< CAN_ERR_* class bits of the latest error frame
  uint64_t malformed = 0;         ///< wrong datagram size or dlc > 8
  uint64_t kernel_drops = 0;      ///< socket receive-queue overflows (SO_RXQ_OVFL)
};

class CanBus {
 public:
  virtual ~CanBus() = default;
  /// Next data or remote frame passing the filters, waiting at most `timeout`. Error frames
  /// and filtered frames are counted in stats() and skipped.
  virtual IoStatus receive(CanFrame& frame, std::chrono::milliseconds timeout) = 0;
  /// Queues one frame for transmission (retries a full TX queue until `timeout`).
  virtual IoStatus send(const CanFrame& frame, std::chrono::milliseconds timeout) = 0;
  /// Replaces the filters; an empty list accepts every frame.
  virtual IoStatus set_filters(std::span<const CanFilter> filters) = 0;
  virtual const CanBusStats& stats() const = 0;
  virtual const std::string& name() const = 0;
};

/// True when `frame` passes `filter` (see CanFilter). Pure; used by SocketCanBus in user space.
bool can_filter_accepts(const CanFilter& filter, uint32_t id, bool extended);
/// Ok, or kInvalidArgument naming the bad field (id beyond 11/29 bits, dlc > 8).
IoStatus validate_can_frame(const CanFrame& frame);

class SocketCanBus final : public CanBus {
 public:
  SocketCanBus() = default;
  ~SocketCanBus() override;
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;

  /// Opens a raw PF_CAN socket bound to `interface_name` (e.g. "can0", "vcan0") with kernel
  /// timestamps, error frames and drop counting enabled. kUnsupported when the kernel has no
  /// CAN (EAFNOSUPPORT), kDisconnected when the interface does not exist.
  IoStatus open_interface(const std::string& interface_name);
  /// Takes ownership of a connected SOCK_SEQPACKET socket carrying `struct can_frame` datagrams.
  IoStatus adopt_socket(int fd, std::string name);
  void close();
  bool is_open() const { return fd_ >= 0; }

  IoStatus receive(CanFrame& frame, std::chrono::milliseconds timeout) override;
  IoStatus send(const CanFrame& frame, std::chrono::milliseconds timeout) override;
  IoStatus set_filters(std::span<const CanFilter> filters) override;
  const CanBusStats& stats() const override { return stats_; }
  const std::string& name() const override { return name_; }

 private:
  IoStatus enable_timestamps();
  /// One recvmsg(); Ok with `accepted` false when the datagram was counted and skipped.
  IoStatus receive_one(CanFrame& frame, bool& accepted);

  int fd_ = -1;
  bool kernel_can_ = false;  ///< PF_CAN socket: filters are also installed in the kernel
  std::string name_ = "can";
  std::vector<CanFilter> filters_;
  CanBusStats stats_;
};

/// A connected pair of buses over socketpair(AF_UNIX, SOCK_SEQPACKET): what one sends, the
/// other receives, through the same framing/filter/timestamp code as a real PF_CAN socket.
IoStatus open_can_socketpair(SocketCanBus& a, SocketCanBus& b);

}  // namespace nav::drivers
