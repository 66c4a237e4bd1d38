#pragma once
// Camera side of the playback (dive_player.h): Aravis' fake GigE Vision camera served in this
// process on the loopback interface (arv_gv_fake_camera_new_full("lo", ...), GVCP on
// 127.0.0.1:3956 and GVSP streaming through the kernel's UDP stack), which navd opens as
// camera_id 127.0.0.1. Only one can listen per network namespace.
//
// It plays the vehicle's triggered 12-bit camera: the GenICam description is the stock fake's
// with Mono12 and Mono12Packed added to PixelFormat (navd's `mono12` opens Mono12Packed) and
// "Line1" added to TriggerSource with the value of "Software", so navd configures hardware
// triggering on Line1 (config/rov.yaml) and the player is the trigger line: fire() writes the
// fake's software-trigger register in-process. The fake acknowledges a trigger at its next
// frame tick (measured up to ~100 ms later), so fire() is called `lead` early and the
// fill-pattern callback, which runs on the fake's thread just before the frame's GVSP packets
// are sent, sleeps until the due time: the frame leaves at the due time (within the sleep's
// wake-up), not at the fake's tick. The frame's pixels are the image given to fire(), or, with
// none, a 12-bit test pattern that changes with the frame number.
//
// Threads: start()/fire()/stats() from the player's threads, vanish()/reappear() from the one
// that fires; the fill callback on Aravis' fake camera thread (joined by vanish()). A mutex
// guards the pending frame.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

struct _ArvBuffer;

namespace nav::hil {

struct FakeCameraStats {
  std::int64_t fired = 0;       ///< fire() calls
  std::int64_t sent = 0;        ///< frames filled for a fire() (their GVSP packets follow)
  std::int64_t from_image = 0;  ///< of `sent`, with the image given to fire()
  std::int64_t not_taken = 0;   ///< fire()s the fake had not acknowledged by the next fire()
  std::int64_t unasked = 0;     ///< frames nobody fired (e.g. navd in free-run): test pattern
  double max_late_s = 0.0;      ///< worst fill time after the due time
  double mean_late_s = 0.0;     ///< over `sent`
};

class FakeGigeCamera {
 public:
  FakeGigeCamera() = default;
  ~FakeGigeCamera();
  FakeGigeCamera(const FakeGigeCamera&) = delete;
  FakeGigeCamera& operator=(const FakeGigeCamera&) = delete;

  /// Starts the fake with this serial number and a width x height Mono12Packed frame (navd
  /// keeps the camera's region); "" on success, else why not.
  std::string start(const std::string& serial, int width_px = 1280, int height_px = 1024);
  bool running() const { return camera_ != nullptr; }
  /// Destroys the fake (its GVCP and GVSP sockets close, its thread ends): the camera vanishes
  /// from the network; a pending fire() is dropped. No-op when not running.
  void vanish();
  /// Starts it again with start()'s last serial and frame size; "" or why not.
  std::string reappear();
  /// The address navd opens it by.
  static constexpr const char* kAddress = "127.0.0.1";

  /// Triggers one frame whose packets leave at host CLOCK_MONOTONIC `due_monotonic_us` (call it
  /// at least ~100 ms before). `image`: CV_16UC1 with 12 significant bits (a rendered PNG),
  /// cropped / zero-padded to the camera's region; empty: the test pattern.
  void fire(cv::Mat image, std::int64_t due_monotonic_us);
  /// Whether the last fire() has been sent.
  bool idle() const;
  FakeCameraStats stats() const;

  /// The test pattern's pixel (x, y) of frame `n` (12 bits).
  static std::uint16_t pattern_value(int x, int y, std::int64_t n);

 private:
  static void fill(_ArvBuffer* buffer, void* self, std::uint32_t exposure_us, std::uint32_t gain,
                   std::uint32_t pixel_format);
  void fill_buffer(_ArvBuffer* buffer, std::uint32_t pixel_format);

  void* camera_ = nullptr;  ///< ArvGvFakeCamera*
  std::string serial_;
  int width_px_ = 0, height_px_ = 0;
  std::filesystem::path genicam_path_;
  mutable std::mutex mutex_;
  bool pending_ = false;
  cv::Mat pending_image_;
  std::int64_t pending_due_us_ = 0;
  std::int64_t pattern_frames_ = 0;
  FakeCameraStats stats_;
  double late_sum_s_ = 0.0;
};

}  // namespace nav::hil
