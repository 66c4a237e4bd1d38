// The checkpoint thread (checkpoint/checkpoint_worker.h): offers are written or superseded
// and the last one is flushed on stop, write errors are counted and the thread goes on; and
// the resume point (checkpoint/resume_point.h): which measurements a resumed filter skips, and
// its section round trip.
#include "nav/daemon/checkpoint/checkpoint_worker.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "nav/core/serialization/sections.h"
#include "nav/daemon/checkpoint/checkpoint.h"
#include "nav/daemon/checkpoint/resume_point.h"

namespace nav::daemon {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;
using core::SectionSet;
using core::SectionWriter;

TEST(ResumeSkipper, SkipsThePrefixAppliedIncludingTies) {
  auto at = [](std::int64_t t) { return Measurement{Depth{MeasurementTime{t, 0, 0, 0}, 1.0}}; };
  AppliedTracker tracker;
  for (std::int64_t t : {10, 20, 20}) tracker.applied(at(t));
  EXPECT_EQ(tracker.point().validity_us, 20);
  EXPECT_EQ(tracker.point().applied_at_validity, 2u);
  EXPECT_EQ(tracker.point().applied, 3u);
  ResumeSkipper skipper(tracker.point());
  std::vector<bool> skipped;
  for (std::int64_t t : {5, 10, 20, 20, 20, 15, 30}) skipped.push_back(skipper.skip(at(t)));
  EXPECT_EQ(skipped, (std::vector<bool>{true, true, true, true, false, true, false}));
  EXPECT_EQ(skipper.skipped(), 5u);
  SectionWriter w;
  ASSERT_TRUE(add_resume_section(tracker.point(), &w).ok());
  const Bytes bytes = w.finish();
  SectionSet set;
  ASSERT_TRUE(SectionSet::decode(bytes, &set).ok());
  ResumePoint p;
  ASSERT_TRUE(restore_resume_point(set, &p).ok());
  EXPECT_EQ(p.validity_us, 20);
  EXPECT_EQ(p.applied_at_validity, 2u);
}

TEST(CheckpointWorker, OffersAreWrittenSupersededAndFlushedOnStop) {
  const fs::path dir =
      fs::temp_directory_path() / ("checkpoint_worker_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  {
    CheckpointWorker worker(dir, 2);
    for (std::uint8_t i = 0; i < 50; ++i) {
      Bytes payload(1000, i);
      EXPECT_TRUE(worker.offer(7, std::move(payload)));
      EXPECT_TRUE(payload.empty());  // moved, no copy kept by the caller
    }
    worker.stop();
    EXPECT_FALSE(worker.offer(7, Bytes(10, 0)));
    const CheckpointWorkerStats s = worker.stats();
    EXPECT_EQ(s.offered, 50u);
    EXPECT_EQ(s.written + s.superseded, 50u);  // each offer is written or replaced
    EXPECT_EQ(s.failed, 0u);
    EXPECT_GE(s.written, 1u);
  }
  // The last offer (the shutdown checkpoint) is on disk, and only `keep` files remain.
  const LoadResult r = load_newest_valid(dir);
  ASSERT_TRUE(r.checkpoint.has_value());
  EXPECT_EQ(r.checkpoint->payload, Bytes(1000, 49));
  EXPECT_EQ(r.checkpoint->payload_version, 7u);
  EXPECT_LE(list_checkpoints(dir).size(), 2u);
  fs::remove_all(dir);
}

TEST(CheckpointWorker, WriteErrorsAreCountedAndTheThreadGoesOn) {
  const fs::path dir =
      fs::temp_directory_path() / ("checkpoint_worker_err_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  CheckpointWorker worker(dir, 2);
  fs::remove_all(dir);  // the directory vanishes under the worker
  worker.offer(1, Bytes(10, 1));
  worker.flush();
  CheckpointWorkerStats s = worker.stats();
  EXPECT_EQ(s.failed, 1u);
  EXPECT_NE(s.last_error.find(dir.string()), std::string::npos) << s.last_error;
  fs::create_directories(dir);
  worker.offer(1, Bytes(10, 2));
  worker.flush();
  s = worker.stats();
  EXPECT_EQ(s.written, 1u);
  worker.stop();
  fs::remove_all(dir);
}

TEST(ResumePoint, InconsistentCountsAreRefused) {
  ResumePoint bad;
  bad.validity_us = 5;
  bad.applied_at_validity = 3;
  bad.applied = 2;  // fewer in all than at T
  SectionWriter w;
  ASSERT_TRUE(add_resume_section(bad, &w).ok());
  const Bytes bytes = w.finish();
  SectionSet set;
  ASSERT_TRUE(SectionSet::decode(bytes, &set).ok());
  ResumePoint p;
  const core::Status s = restore_resume_point(set, &p);
  EXPECT_NE(s.message().find("3 applied at T but 2 in all"), std::string::npos) << s.message();
  EXPECT_EQ(p.applied, 0u);  // unchanged on error
}

}  // namespace
}  // namespace nav::daemon
