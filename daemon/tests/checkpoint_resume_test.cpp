// Checkpoints end to end at library level ("nothing lost"): a dive (the
// simulated survey of core/sim, with PCG recovery and Algorithm 1 bounds driven as navd does)
// runs in a child process that checkpoints the map through the CheckpointWorker thread every few
// steps and on completion; the parent kills it with SIGKILL at random moments, restarts it each
// time, and the restarted child resumes from the newest valid checkpoint, skipping the steps
// that checkpoint already contains. The final map must equal an uninterrupted run's bit for bit
// (the steps after the last checkpoint are replayed from the log), with every delayed state.
// The same with navd's NavFilter on the synthetic dive of support/synthetic_dive.h: the child
// skips the measurements the checkpoint contains by their time of validity (ResumeSkipper).
// A further test corrupts and truncates the newest checkpoints: they are reported with their
// reason and skipped, the previous one is resumed, and the result is still bit-identical.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "nav/core/navigation/nav_filter.h"
#include "nav/core/serialization/byte_io.h"
#include "nav/core/serialization/map_codec.h"
#include "nav/core/sim/survey.h"
#include "nav/daemon/checkpoint/checkpoint.h"
#include "nav/daemon/checkpoint/checkpoint_worker.h"
#include "nav/daemon/checkpoint/nav_filter_checkpoint.h"
#include "nav/daemon/checkpoint/resume_point.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "support/nav_filter_fixture.h"
#include "support/synthetic_dive.h"

namespace nav::daemon {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;
using core::SectionSet;
using core::SectionWriter;
using core::Status;

constexpr std::uint32_t kPayloadVersion = 1;
constexpr std::uint32_t kDiveSectionTag = core::section_tag("SURV");
constexpr int kCheckpointEverySteps = 6;

core::sim::Survey make_survey() {
  core::sim::SurveyOptions o;
  o.num_images = 60;
  o.images_per_line = 10;
  o.seed = 11;
  return core::sim::simulate_survey(o);
}

/// navd's default (block Jacobi). Not the factor preconditioner: CHOLMOD's OpenMP thread pool,
/// once started in this process, deadlocks the fork()ed children that use it again.
core::StateRecoveryOptions recovery_options() {
  core::StateRecoveryOptions o = core::block_jacobi_recovery();
  o.iterations_per_step = 30;
  return o;
}

/// The dive's map and its position in the log: what a checkpoint holds.
struct Dive {
  explicit Dive(const core::sim::Survey& s)
      : survey(&s), filter(12), bounds(12), recovery(12, recovery_options()) {
    (void)filter.initialize(s.x0_mean, s.P0);
    (void)bounds.initialize_robot(s.P0);
    (void)recovery.initialize(s.x0_mean, s.P0);
  }

  /// One survey step as navd's filter thread would do it; false on a filter error.
  bool step() {
    const core::sim::SurveyStep& st = survey->steps[next_step];
    core::Mat12 F, Q;
    const core::Vec12 f =
        core::sim::predicted_mean(*survey, st, filter.mean_block(core::Esdf::kRobotBlock), &F, &Q);
    const int blocks_before = filter.num_blocks();
    if (!core::sim::apply_step(*survey, st, filter, image_blocks).ok()) return false;
    const bool keep = st.image >= 0;
    if (!bounds.predict_robot(F, Q, keep, keep ? image_blocks.back() : -1).ok()) return false;
    if (!recovery.extend_for_prediction(F, Q, f, keep, keep ? blocks_before : -1).ok()) {
      return false;
    }
    ++next_step;
    if (!keep) return true;
    const core::RecoveryResult r =
        recovery.solve(filter.information(), filter.information_vector());
    if (!r.status.ok() || !filter.set_mean(recovery.mean()).ok()) return false;
    if (!bounds
             .set_recovery(recovery.robot_covariance(), r.column_residual_frobenius,
                           filter.num_blocks())
             .ok()) {
      return false;
    }
    for (const core::sim::CameraLink& link : st.links) {
      const int a = image_blocks[static_cast<size_t>(link.image_a)];
      const int b = image_blocks[static_cast<size_t>(link.image_b)];
      core::MeasJac Ha, Hb;
      survey->camera.predict(filter.mean_block(a), filter.mean_block(b), &Ha, &Hb);
      core::LinkProposal p;
      if (!bounds.propose(a, recovery.cross_covariance(a), &p).ok()) return false;
      (void)bounds.update(p, Hb, Ha, survey->R_camera);
    }
    return true;
  }

  /// The checkpoint payload: map sections plus the dive's own (next step, image -> block).
  Bytes encode() const {
    SectionWriter w;
    (void)core::add_map_sections(filter, &bounds, &w);
    (void)core::add_recovery_section(recovery, &w);
    core::ByteWriter dive;
    dive.u64(next_step);
    dive.u32(static_cast<std::uint32_t>(image_blocks.size()));
    for (int b : image_blocks) dive.u32(static_cast<std::uint32_t>(b));
    (void)w.add(kDiveSectionTag, 1, dive.data());
    return w.finish();
  }

  /// Restores everything from a payload or returns the reason (nothing changed then).
  std::string restore(const Bytes& payload) {
    SectionSet set;
    std::optional<core::Esdf> f;
    std::optional<core::CovarianceBounds> b;
    if (Status s = SectionSet::decode(payload, &set); !s.ok()) return s.to_string();
    if (Status s = core::restore_map(set, &f, &b); !s.ok()) return s.to_string();
    core::StateRecovery rec(12, recovery_options());
    if (Status s = core::restore_recovery(set, f->num_blocks(), &rec); !s.ok())
      return s.to_string();
    const core::SectionView* v = nullptr;
    if (Status s = set.require(kDiveSectionTag, 1, &v); !s.ok()) return s.to_string();
    core::ByteReader r(v->bytes, "SURV section", v->offset);
    std::uint64_t step = 0;
    std::uint32_t n = 0;
    if (Status s = r.u64(&step, "next step"); !s.ok()) return s.to_string();
    if (Status s = r.u32(&n, "images"); !s.ok()) return s.to_string();
    if (Status s = r.check_count(n, 4, "images"); !s.ok()) return s.to_string();
    std::vector<int> blocks(n);
    for (int& block : blocks) {
      std::uint32_t x = 0;
      if (Status s = r.u32(&x, "image block"); !s.ok()) return s.to_string();
      if (x < 1 || x >= static_cast<std::uint32_t>(f->num_blocks())) return "bad image block";
      block = static_cast<int>(x);
    }
    if (step > survey->steps.size()) return "next step beyond the dive";
    filter = std::move(*f);
    bounds = std::move(*b);
    recovery = std::move(rec);
    next_step = step;
    image_blocks = std::move(blocks);
    return "";
  }

  const core::sim::Survey* survey;
  core::Esdf filter;
  core::CovarianceBounds bounds;
  core::StateRecovery recovery;
  std::size_t next_step = 0;
  std::vector<int> image_blocks;
};

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The child: resume (or start), run to the end with periodic checkpoints, checkpoint on
/// completion, write the final map to final.bin. Logs each start to starts.log.
[[noreturn]] void run_child(const core::sim::Survey& survey, const fs::path& dir) {
  Dive dive(survey);
  const LoadResult loaded = load_newest_valid(
      dir / "checkpoints", [&dive](const Checkpoint& c) { return dive.restore(c.payload); });
  {
    std::ofstream log(dir / "starts.log", std::ios::app);
    log << "start " << dive.next_step << " skipped " << loaded.skipped.size();
    for (const SkippedCheckpoint& s : loaded.skipped) {
      log << " [" << s.path.filename().string() << ": " << s.reason << "]";
    }
    log << "\n";
  }
  CheckpointWorker worker(dir / "checkpoints", 3);
  while (dive.next_step < survey.steps.size()) {
    if (!dive.step()) std::_Exit(3);
    if (dive.next_step % kCheckpointEverySteps == 0) worker.offer(kPayloadVersion, dive.encode());
  }
  worker.offer(kPayloadVersion, dive.encode());  // the shutdown checkpoint
  worker.stop();
  const Bytes final_map = dive.encode();
  std::ofstream(dir / "final.tmp", std::ios::binary)
      .write(reinterpret_cast<const char*>(final_map.data()),
             static_cast<std::streamsize>(final_map.size()));
  fs::rename(dir / "final.tmp", dir / "final.bin");
  std::_Exit(0);
}

class CheckpointResume : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("checkpoint_resume_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// Starts a child; returns its pid.
  pid_t start(const core::sim::Survey& survey) {
    const pid_t pid = ::fork();
    if (pid == 0) run_child(survey, dir_);
    return pid;
  }
  /// Waits for the child; its exit code, or -signal.
  static int wait(pid_t pid) {
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  }

  fs::path dir_;
};

TEST_F(CheckpointResume, KilledAtRandomPointsResumesToTheSameMap) {
  const core::sim::Survey survey = make_survey();
  // The uninterrupted run (in process) and its duration, to place the kills.
  const auto t0 = std::chrono::steady_clock::now();
  Dive reference(survey);
  while (reference.next_step < survey.steps.size()) ASSERT_TRUE(reference.step());
  const Bytes expected = reference.encode();
  const double run_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(reference.image_blocks.size(), 60u);

  std::mt19937 rng(5);
  int kills = 0;
  for (int attempt = 0; attempt < 12 && kills < 5; ++attempt) {
    const pid_t pid = start(survey);
    std::uniform_real_distribution<double> when_ms(0.2 * run_ms, 1.2 * run_ms);
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(when_ms(rng)));
    ::kill(pid, SIGKILL);
    const int code = wait(pid);
    if (code == -SIGKILL) ++kills;
    if (code == 0) fs::remove(dir_ / "final.bin");  // finished before the kill: start over
    if (code == 0) fs::remove_all(dir_ / "checkpoints");
    ASSERT_TRUE(code == 0 || code == -SIGKILL) << "child failed with " << code;
  }
  EXPECT_GE(kills, 3) << "the run is too short to be killed mid-way";
  const pid_t last = start(survey);
  ASSERT_EQ(wait(last), 0);
  const std::string log = slurp(dir_ / "starts.log");
  std::printf("uninterrupted %.0f ms, %d kills; starts (next step, skipped):\n%s", run_ms, kills,
              log.c_str());
  // At least one restart resumed from a checkpoint part-way through the dive.
  EXPECT_TRUE(std::regex_search(log, std::regex("start [1-9][0-9]* "))) << log;

  const std::string got = slurp(dir_ / "final.bin");
  ASSERT_EQ(got.size(), expected.size());
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(),
                         reinterpret_cast<const std::uint8_t*>(got.data())))
      << "the resumed map differs from the uninterrupted one";
  Dive resumed(survey);
  ASSERT_EQ(resumed.restore(Bytes(got.begin(), got.end())), "");
  EXPECT_EQ(resumed.filter.num_blocks(), 61);  // robot + every delayed state
  EXPECT_EQ(resumed.bounds.num_bounds(), 60);
}

TEST_F(CheckpointResume, CorruptAndTruncatedNewestAreReportedAndSkipped) {
  const core::sim::Survey survey = make_survey();
  Dive reference(survey);
  while (reference.next_step < survey.steps.size()) ASSERT_TRUE(reference.step());
  const Bytes expected = reference.encode();

  // Three checkpoints part-way (steps 60, 120, 180) as a killed run leaves them.
  {
    Dive dive(survey);
    CheckpointWriter writer(dir_ / "checkpoints", 3);
    while (dive.next_step < 180) {
      ASSERT_TRUE(dive.step());
      if (dive.next_step % 60 == 0) {
        ASSERT_TRUE(writer.write(kPayloadVersion, dive.encode()).ok);
      }
    }
  }
  const std::vector<std::uint64_t> seqs = list_checkpoints(dir_ / "checkpoints");
  ASSERT_EQ(seqs.size(), 3u);
  // Newest truncated; second newest with one flipped payload byte.
  const fs::path newest = checkpoint_path(dir_ / "checkpoints", seqs[2]);
  fs::resize_file(newest, fs::file_size(newest) / 2);
  const fs::path middle = checkpoint_path(dir_ / "checkpoints", seqs[1]);
  {
    std::fstream f(middle, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(kCheckpointHeaderBytes + 1000));
    char c = 0;
    f.read(&c, 1);
    f.seekp(static_cast<std::streamoff>(kCheckpointHeaderBytes + 1000));
    c = static_cast<char>(c ^ 0x04);
    f.write(&c, 1);
  }
  const pid_t pid = start(survey);
  ASSERT_EQ(wait(pid), 0);
  const std::string log = slurp(dir_ / "starts.log");
  std::printf("%s", log.c_str());
  EXPECT_NE(log.find("start 60 skipped 2"), std::string::npos) << log;
  EXPECT_NE(log.find(newest.filename().string() + ": truncated"), std::string::npos) << log;
  EXPECT_NE(log.find(middle.filename().string() + ": payload CRC-32 mismatch"), std::string::npos)
      << log;
  const std::string got = slurp(dir_ / "final.bin");
  EXPECT_TRUE(got.size() == expected.size() &&
              std::equal(expected.begin(), expected.end(),
                         reinterpret_cast<const std::uint8_t*>(got.data())));
}

TEST_F(CheckpointResume, PayloadThatDoesNotDecodeIsSkippedWithItsReason) {
  const core::sim::Survey survey = make_survey();
  CheckpointWriter writer(dir_ / "checkpoints", 3);
  Dive dive(survey);
  while (dive.next_step < 12) ASSERT_TRUE(dive.step());
  ASSERT_TRUE(writer.write(kPayloadVersion, dive.encode()).ok);
  // A file whose own checksums are fine but whose payload is not a map container.
  const Bytes junk = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
  ASSERT_TRUE(writer.write(kPayloadVersion, junk).ok);
  Dive resumed(survey);
  const LoadResult r = load_newest_valid(
      dir_ / "checkpoints", [&resumed](const Checkpoint& c) { return resumed.restore(c.payload); });
  ASSERT_TRUE(r.checkpoint.has_value());
  EXPECT_EQ(resumed.next_step, 12u);
  ASSERT_EQ(r.skipped.size(), 1u);
  EXPECT_NE(r.skipped[0].reason.find("bad magic (not NAVSECTS)"), std::string::npos)
      << r.skipped[0].reason;
}

// ---- NavFilter ----------------------------------------------------------------------------

struct FilterDive {
  FilterDive() {
    config = nav::testing::synthetic_dive_config();  // ctest runs in the source directory
    nav::testing::use_block_jacobi(config);          // bit-identical, and fork() below
    nav::testing::SyntheticDiveOptions o;
    o.duration_s = 120.0;
    dive = nav::testing::make_synthetic_dive(config, o);
    options = filter_options_from_config(config);
  }
  std::unique_ptr<NavFilter> make() const {
    return std::make_unique<NavFilter>(options, &dive.registrations);
  }
  NavdConfig config;
  nav::testing::SyntheticDive dive;
  NavFilterOptions options;
};

Bytes encode_filter(const NavFilter& f, const ResumePoint* point) {
  SectionWriter w;
  (void)add_nav_filter_sections(f, &w);
  if (point != nullptr) (void)add_resume_section(*point, &w);
  return w.finish();
}

/// navd's loop in miniature: resume, skip what the checkpoint holds, filter, checkpoint every
/// 40 measurements and at the end (the shutdown checkpoint, before finish()), then finish().
[[noreturn]] void run_filter_child(const FilterDive& fx, const fs::path& dir) {
  std::unique_ptr<NavFilter> filter = fx.make();
  ResumePoint point;
  const LoadResult loaded =
      load_newest_valid(dir / "checkpoints", [&](const Checkpoint& c) -> std::string {
        SectionSet set;
        std::unique_ptr<NavFilter> restored = fx.make();
        ResumePoint p;
        if (Status s = SectionSet::decode(c.payload, &set); !s.ok()) return s.to_string();
        if (Status s = restore_nav_filter(set, restored.get()); !s.ok()) return s.to_string();
        if (Status s = restore_resume_point(set, &p); !s.ok()) return s.to_string();
        filter = std::move(restored);
        point = p;
        return "";
      });
  std::ofstream(dir / "starts.log", std::ios::app) << "start " << point.applied << " skipped "
                                                   << loaded.skipped.size() <<
      [&] {
        std::string reasons;
        for (const SkippedCheckpoint& k : loaded.skipped) {
          reasons += " [" + k.path.filename().string() + ": " + k.reason + "]";
        }
        return reasons;
      }() << "\n";
  CheckpointWorker worker(dir / "checkpoints", 3);
  AppliedTracker tracker(point);
  ResumeSkipper skipper(point);
  for (const Measurement& m : fx.dive.measurements) {
    if (skipper.skip(m)) continue;
    if (!filter->process(m).ok()) std::_Exit(3);
    tracker.applied(m);
    if (tracker.point().applied % 40 == 0) {
      worker.offer(kPayloadVersion, encode_filter(*filter, &tracker.point()));
    }
  }
  worker.offer(kPayloadVersion, encode_filter(*filter, &tracker.point()));
  worker.stop();
  if (!filter->finish().ok()) std::_Exit(4);
  const Bytes final_map = encode_filter(*filter, nullptr);
  std::ofstream(dir / "final.tmp", std::ios::binary)
      .write(reinterpret_cast<const char*>(final_map.data()),
             static_cast<std::streamsize>(final_map.size()));
  fs::rename(dir / "final.tmp", dir / "final.bin");
  std::_Exit(0);
}

TEST_F(CheckpointResume, NavFilterKilledAtRandomPointsResumesToTheSameMap) {
  const FilterDive fx;
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<NavFilter> reference = fx.make();
  for (const Measurement& m : fx.dive.measurements) ASSERT_TRUE(reference->process(m).ok());
  ASSERT_TRUE(reference->finish().ok());
  const Bytes expected = encode_filter(*reference, nullptr);
  const double run_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  std::mt19937 rng(9);
  int kills = 0;
  for (int attempt = 0; attempt < 12 && kills < 5; ++attempt) {
    const pid_t pid = ::fork();
    if (pid == 0) run_filter_child(fx, dir_);
    std::uniform_real_distribution<double> when_ms(0.2 * run_ms, 1.2 * run_ms);
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(when_ms(rng)));
    ::kill(pid, SIGKILL);
    const int code = wait(pid);
    if (code == -SIGKILL) ++kills;
    if (code == 0) {  // finished before the kill: start over
      fs::remove(dir_ / "final.bin");
      fs::remove_all(dir_ / "checkpoints");
    }
    ASSERT_TRUE(code == 0 || code == -SIGKILL) << "child failed with " << code;
  }
  EXPECT_GE(kills, 3) << "the run is too short to be killed mid-way";
  const pid_t last = ::fork();
  if (last == 0) run_filter_child(fx, dir_);
  ASSERT_EQ(wait(last), 0);
  const std::string log = slurp(dir_ / "starts.log");
  std::printf(
      "NavFilter: uninterrupted %.0f ms, %zu measurements, %d kills; starts (applied "
      "measurements):\n%s",
      run_ms, fx.dive.measurements.size(), kills, log.c_str());
  EXPECT_TRUE(std::regex_search(log, std::regex("start [1-9][0-9]* "))) << log;
  const std::string got = slurp(dir_ / "final.bin");
  ASSERT_EQ(got.size(), expected.size());
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(),
                         reinterpret_cast<const std::uint8_t*>(got.data())))
      << "the resumed NavFilter differs from the uninterrupted one";
  std::unique_ptr<NavFilter> resumed = fx.make();
  SectionSet set;
  const Bytes got_bytes(got.begin(), got.end());
  ASSERT_TRUE(SectionSet::decode(got_bytes, &set).ok());
  ASSERT_TRUE(restore_nav_filter(set, resumed.get()).ok());
  EXPECT_EQ(resumed->esdf().num_blocks(), reference->esdf().num_blocks());  // no state lost
  EXPECT_EQ(resumed->images().size(), fx.dive.image_truth.size());
  EXPECT_EQ(resumed->links().size(), reference->links().size());
}

}  // namespace
}  // namespace nav::daemon
