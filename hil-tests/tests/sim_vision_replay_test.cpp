// navd registering its own frames in replay (config vision.enabled, nav/daemon/vision/
// vision_link.h) on a short rendered survey: two runs give identical links and poses (answers
// applied at data times, whatever the threads' speed), consecutive frames register, and
// missing, corrupt or wrong-size frames are failed answers with their reason while the filter
// keeps navigating on the other sensors; answers carry their inliers and largest leverage, and
// the config's leverage limit refuses registrations.
#include <gtest/gtest.h>

#include <filesystem>
#include <chrono>
#include <fstream>
#include <mutex>
#include <thread>
#include <vector>
#include <opencv2/imgcodecs.hpp>

#include "nav/daemon/config/config.h"
#include "nav/daemon/replay/dive_replay.h"
#include "nav/daemon/sources/camera_source.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

namespace fs = std::filesystem;
const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

/// One rendered dive shared by the tests (rendering is the slow part).
const fs::path& dive() {
  static const fs::path dir = [] {
    const fs::path d = scratch_dir("vision_replay");
    SimOptions o = sim_options(d, 3, 4);
    o.render_images = true;
    simulate_dive(o, sim_config_path().string());
    return d;
  }();
  return dir;
}

daemon::NavdConfig vision_config(const fs::path& image_dir = {}) {
  daemon::NavdConfig c = daemon::load_config_file((dive() / "config.yaml").string());
  c.vision.enabled = true;
  c.vision.threads = 2;
  c.vision.image_dir = image_dir.string();
  c.vision.image_width_px = 1280;
  c.vision.image_height_px = 1024;
  c.filter.registration_wait_s = 8.0;
  return c;
}

daemon::ReplayRun replay(const daemon::NavdConfig& config, daemon::ReplayOptions o = {}) {
  o.dead_reckoning = false;
  return daemon::run_replay((dive() / "dive.lcmlog").string(), config, o);
}

TEST(SimVisionReplay, TwoRunsGiveIdenticalLinksAndPoses) {
  const daemon::ReplayRun a = replay(vision_config());
  const daemon::ReplayRun b = replay(vision_config());
  ASSERT_TRUE(a.error.empty()) << a.error;
  ASSERT_TRUE(a.vision.has_value());
  EXPECT_GT(a.vision->worker.submitted, 0u);
  EXPECT_EQ(a.vision->worker.answered, a.vision->worker.submitted);
  EXPECT_GT(a.vision->worker.succeeded, 0u) << a.vision->worker.last_failure;
  EXPECT_GT(a.slam->counters().links_accepted, 0u);
  ASSERT_EQ(a.slam->links().size(), b.slam->links().size());
  for (std::size_t k = 0; k < a.slam->links().size(); ++k) {
    const auto& la = a.slam->links()[k];
    const auto& lb = b.slam->links()[k];
    EXPECT_EQ(la.frame_i, lb.frame_i);
    EXPECT_EQ(la.frame_j, lb.frame_j);
    EXPECT_EQ(la.outcome, lb.outcome);
    EXPECT_EQ(la.z, lb.z) << "link " << k;
  }
  EXPECT_EQ(a.slam->esdf().mean_block(0), b.slam->esdf().mean_block(0));
}

TEST(SimVisionReplay, BadFramesFailTheirPairsAndTheFilterNavigatesOn) {
  const fs::path images = scratch_dir("vision_bad_frames");
  fs::copy(dive() / "images", images);
  fs::remove(images / daemon::frame_png_name(1));                      // missing
  std::ofstream(images / daemon::frame_png_name(2), std::ios::trunc) << "\x89PNG truncated";
  cv::imwrite((images / daemon::frame_png_name(3)).string(), cv::Mat(64, 64, CV_16UC1, 900));
  const daemon::ReplayRun run = replay(vision_config(images));
  ASSERT_TRUE(run.error.empty()) << run.error;
  ASSERT_TRUE(run.vision.has_value());
  const auto& w = run.vision->worker;
  EXPECT_EQ(w.answered, w.submitted);
  // Every pair has a bad frame (frames 1-3 of 0-3): all answered success = false.
  EXPECT_GT(w.submitted, 0u);
  EXPECT_EQ(w.failed, w.submitted);
  EXPECT_NE(w.last_failure.find("frame "), std::string::npos) << w.last_failure;
  // Every image was still filtered with the other sensors.
  EXPECT_EQ(run.slam->counters().images, 4u);
  EXPECT_GT(run.slam->counters().updates, 100u);
  EXPECT_EQ(run.slam->counters().update_failures, 0u);
  // No pair with a bad frame became a link.
  for (const auto& l : run.slam->links()) {
    const bool bad = (l.frame_i >= 1 && l.frame_i <= 3) || (l.frame_j >= 1 && l.frame_j <= 3);
    if (bad) {
      EXPECT_NE(l.outcome, daemon::LinkOutcome::kAccepted) << l.frame_i << "-" << l.frame_j;
    }
  }
}

TEST(SimVisionReplay, AnswersCarryInliersAndLeverageAndTheLeverageLimitRefuses) {
  const daemon::ReplayRun run = replay(vision_config());
  ASSERT_TRUE(run.error.empty()) << run.error;
  int succeeded = 0;
  for (const auto& a : run.vision_answers) {
    if (!a.registration.success) continue;
    ++succeeded;
    EXPECT_GE(a.inliers, 12) << a.registration.frame_id_i << "-" << a.registration.frame_id_j;
    // n inliers' leverages sum to 5: the largest is in [5 / n, 1].
    EXPECT_GE(a.max_leverage, 5.0 / a.inliers);
    EXPECT_LE(a.max_leverage, 1.0);
  }
  ASSERT_GT(succeeded, 0);
  // A limit below 5 / n refuses every registration that reaches the check, with the reason.
  daemon::NavdConfig strict = vision_config();
  strict.vision.max_leverage = 1e-3;
  const daemon::ReplayRun refused = replay(strict);
  ASSERT_TRUE(refused.error.empty()) << refused.error;
  EXPECT_EQ(refused.vision->worker.succeeded, 0u);
  int by_leverage = 0;
  for (const auto& a : refused.vision_answers) {
    if (a.reason.find("decides a direction of the pose alone") == std::string::npos) continue;
    ++by_leverage;
    EXPECT_GT(a.max_leverage, 1e-3);
  }
  EXPECT_GT(by_leverage, 0);
}

TEST(SimVisionReplay, LiveLinkAnswersEveryProposalPastItsDeadlineAsExpired) {
  // The live link (kLive) sees the same deferred pairs; their deadlines are on the log's
  // CLOCK_REALTIME, long past by now, so each is answered "expired: deadline passed" without
  // work, with its pose prior built from the filter (no "without prior").
  const fs::path empty = scratch_dir("vision_no_frames");
  std::mutex mutex;
  std::vector<daemon::vision::VisionAnswer> answers;
  daemon::vision::VisionLink live(vision_config(), (dive() / "images").string(),
                                  daemon::vision::VisionLink::Mode::kLive,
                                  [&](daemon::vision::VisionAnswer&& a) {
                                    const std::lock_guard<std::mutex> lock(mutex);
                                    answers.push_back(std::move(a));
                                  });
  daemon::ReplayOptions o;
  o.after_measurement = [&](const daemon::NavFilter& f) { live.after_measurement(f); };
  const daemon::ReplayRun run = replay(vision_config(empty), o);  // replay link: no frames
  ASSERT_TRUE(run.error.empty()) << run.error;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (live.stats().worker.answered < live.stats().worker.submitted &&
         std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const daemon::vision::VisionLinkStats s = live.stats();
  EXPECT_GT(s.worker.submitted, 0u);
  EXPECT_EQ(s.worker.submitted, run.vision->worker.submitted) << "same pairs as the replay link";
  EXPECT_EQ(s.without_prior, 0u);
  const std::lock_guard<std::mutex> lock(mutex);
  ASSERT_EQ(answers.size(), s.worker.submitted);
  for (const auto& a : answers) {
    EXPECT_FALSE(a.registration.success);
    EXPECT_TRUE(a.expired);
    EXPECT_EQ(a.reason.rfind("expired: deadline passed", 0), 0u) << a.reason;
  }
}

}  // namespace
}  // namespace nav::sim::test
