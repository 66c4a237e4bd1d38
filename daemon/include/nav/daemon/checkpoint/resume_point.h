#pragma once
// Where the filter stood in its input when a checkpoint was taken, so that a restarted navd
// skips exactly the measurements the checkpointed map already contains.
//
// The filter applies measurements in time-of-validity order (TimeOrderingBuffer; late ones are
// dropped and counted), so "applied" is a prefix in that order: everything with validity before
// T, plus the first k measurements with validity exactly T (ties are applied in input order).
// On resume, ResumeSkipper drops from the replayed input every measurement with validity < T
// (applied, or dropped as late in the first run: the map is the same) and the first k at T; the
// rest is applied as in an uninterrupted run, so the map ends bit-identical (tested in
// checkpoint_resume_test.cpp). Stored as the "RSUM" section of the checkpoint payload.

#include <cstdint>
#include <limits>
#include <vector>

#include "nav/core/serialization/sections.h"
#include "nav/core/status.h"
#include "nav/daemon/queue/measurements.h"

namespace nav::daemon {

inline constexpr std::uint32_t kResumeSectionTag = core::section_tag("RSUM");
inline constexpr std::uint32_t kResumeSectionVersion = 1;

struct ResumePoint {
  std::int64_t validity_us = std::numeric_limits<std::int64_t>::min();  ///< T (none yet: min)
  std::uint64_t applied_at_validity = 0;  ///< k: measurements applied with validity == T
  std::uint64_t applied = 0;              ///< all measurements applied (for logs)
};

/// Both directions (core/serialization/archive.h): i64 T, u64 k, u64 applied.
template <class Archive>
void serialize(Archive& ar, ResumePoint& p) {
  ar(p.validity_us, "validity_us");
  ar(p.applied_at_validity, "applied at validity");
  ar(p.applied, "applied");
}

/// Filter thread: call applied(m) after each measurement handed to the filter.
class AppliedTracker {
 public:
  AppliedTracker() = default;
  explicit AppliedTracker(const ResumePoint& start) : point_(start) {}
  void applied(const Measurement& m);
  const ResumePoint& point() const { return point_; }

 private:
  ResumePoint point_;
};

/// Replay source side: skip(m) is true for measurements the checkpoint already contains.
class ResumeSkipper {
 public:
  explicit ResumeSkipper(const ResumePoint& point) : point_(point) {}
  bool skip(const Measurement& m);
  std::uint64_t skipped() const { return skipped_; }

 private:
  ResumePoint point_;
  std::uint64_t ties_skipped_ = 0;
  std::uint64_t skipped_ = 0;
};

core::Status add_resume_section(const ResumePoint& point, core::SectionWriter* writer);
core::Status restore_resume_point(const core::SectionSet& sections, ResumePoint* point);

}  // namespace nav::daemon
