#pragma once
// VisionLink: navd's NavFilter <-> its own vision stage (VisionWorker), on the filter thread.
//
// After each measurement, every pair the filter newly deferred (pending_registrations.h) is
// submitted with its pose prior (camera_prior.h) and deadline. The answers go back two ways:
// * Replay (Mode::kReplay, deterministic): the answer of a pair deferred at image j is applied
//   at data time: it enters the RegistrationTable with available_us = image j's receive time +
//   vision.answer_delay_s, and before_measurement() waits for every answer due at or before the
//   next measurement's receive time before that measurement is filtered. The filter therefore
//   sees the same table at the same measurements whatever the threads' speed; the same log and
//   config give the same outputs. No wall-clock deadline and no queue expiry (the worker blocks
//   the submitter instead), because either would depend on timing.
// * Live (Mode::kLive): the answer goes to the sink (navd publishes it as registration_t on
//   NAV_REGISTRATION, from where the RegistrationListener hands it to the filter like any vision
//   process's answer); the worker expires requests past their deadline or beyond its queue.

#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "nav/core/navigation/nav_filter.h"
#include "nav/core/navigation/registration_table.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/vision/feature_cache.h"
#include "nav/daemon/vision/vision_worker.h"

namespace nav::daemon::vision {

/// One answer applied in replay (vision_answers.csv of navtool replay --vision --out).
struct AppliedAnswer {
  core::Registration registration;  ///< available_us = the data time it was applied at
  std::string reason;               ///< why success == false
  int inliers = 0;                  ///< VisionAnswer's
  double max_leverage = 0.0;        ///< VisionAnswer's
};

struct VisionLinkStats {
  VisionWorkerCounters worker;
  FeatureCacheCounters cache;
  std::uint64_t without_prior = 0;  ///< pairs submitted without a pose prior (reason logged)
  std::uint64_t refused = 0;        ///< answers the table refused (registration_problem)
};

/// nav::vision camera of a camera sensor's calibration (distortion k1 k2 p1 p2 [k3]) with the
/// frame size of `vision`; bits per pixel of its pixel format (mono12: 12, mono16: 16, else 8).
nav::vision::CameraIntrinsics vision_camera(const CameraConfig& camera, const VisionConfig& vision);
int bits_per_pixel(PixelFormat format);
/// Reads `dir`/frame_png_name(frame_id) unchanged; throws std::runtime_error naming the file.
cv::Mat load_frame(const std::string& dir, std::uint64_t frame_id);

/// The replay switch of `navtool replay --vision` and `navtool survey --vision`: sets
/// vision.enabled and, when filter.registration_wait_s does not exceed vision.answer_delay_s
/// (a dive log's config replays complete tables with a wait of 0, while the vision stage
/// answers at data time image + answer_delay_s), raises the wait to kReplayVisionWaitS.
inline constexpr double kReplayVisionWaitS = 8.0;  ///< one image period of config/sim.yaml
void enable_vision_in_replay(NavdConfig& config);

class VisionLink {
 public:
  enum class Mode { kReplay, kLive };
  /// `image_dir`: where the frames are. `live_sink`: where live answers go (kLive). Throws
  /// std::invalid_argument when the config has no camera or an unusable calibration.
  VisionLink(const NavdConfig& config, std::string image_dir, Mode mode,
             VisionWorker::AnswerSink live_sink = {});
  ~VisionLink();

  /// Filter thread, after each measurement the filter processed.
  void after_measurement(const core::NavFilter& filter);
  /// Replay, filter thread, before filtering a measurement received at host_realtime_us.
  void before_measurement(std::int64_t host_realtime_us, core::RegistrationTable& table);
  VisionLinkStats stats() const;
  /// Replay: every answer inserted into the table so far, in proposal order.
  const std::vector<AppliedAnswer>& applied() const { return applied_; }

 private:
  struct Outstanding {
    std::int64_t due_realtime_us = 0;
    std::optional<VisionAnswer> answer;
  };
  void on_answer(VisionAnswer&& answer);

  VisionConfig config_;
  Mode mode_;
  std::int64_t answer_delay_us_;
  core::Vec6 x_body_camera_;
  std::unique_ptr<nav::vision::Registration> registration_;
  std::unique_ptr<FeatureCache> cache_;
  VisionWorker::AnswerSink live_sink_;
  std::uint64_t last_sequence_ = 0;
  std::uint64_t without_prior_ = 0, refused_ = 0;
  mutable std::mutex mutex_;
  std::condition_variable answered_;
  std::map<std::uint64_t, Outstanding> outstanding_;  ///< replay: by sequence
  std::vector<AppliedAnswer> applied_;                ///< replay, filter thread only
  std::unique_ptr<VisionWorker> worker_;              ///< last: stopped first
};

}  // namespace nav::daemon::vision
