#pragma once
// navd's checkpointing of its NavFilter in one place, so that the daemon's
// filter loop needs three calls: resume_nav_filter() at start, after_measurement() after each
// measurement the filter took, shutdown() when stopping. Payload: the sections of
// nav_filter_checkpoint.h plus the resume point (resume_point.h); files, atomicity and rotation:
// checkpoint.h; the writing thread: checkpoint_worker.h.
//
// Threads: after_measurement() and shutdown() run on the filter thread; serialising the map is
// O(map) there once per `checkpoint.period_s` (wall clock), the disk write is on the
// checkpoint thread; with a recovery-thread job in flight it first waits for that job (at most
// one job of fixed iterations) and stores its result (nav_filter_checkpoint.h), so a
// checkpoint can be taken at any measurement. resume_nav_filter() runs once before the threads
// start.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "nav/daemon/checkpoint/checkpoint.h"
#include "nav/daemon/checkpoint/checkpoint_worker.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/checkpoint/resume_point.h"
#include "nav/core/navigation/nav_filter.h"

namespace nav::daemon {

inline constexpr std::uint32_t kNavFilterPayloadVersion = 4;  // 4: NAVF v6, 3: NAVF v5
/// "IDNT": what the checkpointed filter was fed (e.g. the replayed dive log), so that a
/// checkpoint of another input is never resumed.
inline constexpr std::uint32_t kInputIdentitySectionTag = core::section_tag("IDNT");

struct ResumedNavFilter {
  std::unique_ptr<NavFilter> filter;       ///< null when no checkpoint could be resumed
  ResumePoint point;                       ///< what the input must skip (ResumeSkipper)
  std::filesystem::path path;              ///< the checkpoint resumed
  std::vector<SkippedCheckpoint> skipped;  ///< newer ones refused, with the reason
};

/// The newest checkpoint in `dir` that verifies and decodes into a filter made by `make`
/// (built from the current config); newer corrupt, truncated or undecodable ones are listed
/// in `skipped`. A checkpoint whose input identity differs from `identity` is skipped too.
ResumedNavFilter resume_nav_filter(const std::filesystem::path& dir,
                                   const std::function<std::unique_ptr<NavFilter>()>& make,
                                   const std::string& identity = "");

/// The checkpoint payload of `filter` at `point`, fed the input named `identity`.
std::vector<std::uint8_t> nav_filter_payload(const NavFilter& filter, const ResumePoint& point,
                                             const std::string& identity = "");

class NavFilterCheckpointer {
 public:
  /// Starts the checkpoint thread on config.path (throws std::runtime_error if unusable).
  /// `start` is the resume point of a resumed filter (default: nothing applied yet).
  explicit NavFilterCheckpointer(const CheckpointConfig& config, ResumePoint start = {},
                                 std::string identity = "");

  /// After the filter processed `m`: tracks it and offers a checkpoint when period_s of wall
  /// time has passed since the last one.
  void after_measurement(const NavFilter& filter, const Measurement& m);
  /// Offers the shutdown checkpoint and waits for it to be written (call before finish()).
  void shutdown(const NavFilter& filter);

  const ResumePoint& point() const { return tracker_.point(); }
  CheckpointWorkerStats stats() const { return worker_.stats(); }

 private:
  std::chrono::steady_clock::duration period_;
  std::chrono::steady_clock::time_point last_;
  AppliedTracker tracker_;
  std::string identity_;
  CheckpointWorker worker_;
};

}  // namespace nav::daemon
