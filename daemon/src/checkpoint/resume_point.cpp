// Resume position of a checkpointed filter in its time-ordered input (resume_point.h).
#include "nav/daemon/checkpoint/resume_point.h"

#include "nav/core/serialization/archive.h"

namespace nav::daemon {

void AppliedTracker::applied(const Measurement& m) {
  const std::int64_t t = validity_us(m);
  if (t > point_.validity_us) {
    point_.validity_us = t;
    point_.applied_at_validity = 1;
  } else if (t == point_.validity_us) {
    ++point_.applied_at_validity;
  }
  ++point_.applied;
}

bool ResumeSkipper::skip(const Measurement& m) {
  const std::int64_t t = validity_us(m);
  bool drop = t < point_.validity_us;
  if (t == point_.validity_us && ties_skipped_ < point_.applied_at_validity) {
    ++ties_skipped_;
    drop = true;
  }
  if (drop) ++skipped_;
  return drop;
}

core::Status add_resume_section(const ResumePoint& point, core::SectionWriter* writer) {
  return writer->add(kResumeSectionTag, kResumeSectionVersion, core::to_bytes(point));
}

core::Status restore_resume_point(const core::SectionSet& sections, ResumePoint* point) {
  const core::SectionView* v = nullptr;
  if (core::Status s = sections.require(kResumeSectionTag, kResumeSectionVersion, &v); !s.ok()) {
    return s;
  }
  core::ReadArchive ar(v->bytes, "RSUM section", v->offset);
  ResumePoint p;
  ar(p, "resume point");
  ar.check(p.applied_at_validity <= p.applied, std::to_string(p.applied_at_validity) +
                                                   " applied at T but " +
                                                   std::to_string(p.applied) + " in all");
  if (core::Status s = ar.finish(); !s.ok()) return s;
  *point = p;
  return core::Status::Ok();
}

}  // namespace nav::daemon
