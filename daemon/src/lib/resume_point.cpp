// Resume position of a checkpointed filter in its time-ordered input (resume_point.h).
#include "nav/daemon/resume_point.h"

#include "nav/core/serialization/byte_io.h"

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
  core::ByteWriter w;
  w.i64(point.validity_us);
  w.u64(point.applied_at_validity);
  w.u64(point.applied);
  return writer->add(kResumeSectionTag, kResumeSectionVersion, w.data());
}

core::Status restore_resume_point(const core::SectionSet& sections, ResumePoint* point) {
  const core::SectionView* v = nullptr;
  if (core::Status s = sections.require(kResumeSectionTag, kResumeSectionVersion, &v); !s.ok()) {
    return s;
  }
  core::ByteReader r(v->bytes, "RSUM section", v->offset);
  ResumePoint p;
  if (core::Status s = r.i64(&p.validity_us, "validity_us"); !s.ok()) return s;
  if (core::Status s = r.u64(&p.applied_at_validity, "applied at validity"); !s.ok()) return s;
  if (core::Status s = r.u64(&p.applied, "applied"); !s.ok()) return s;
  if (core::Status s = r.expect_end(); !s.ok()) return s;
  if (p.applied_at_validity > p.applied) {
    return r.error(std::to_string(p.applied_at_validity) + " applied at T but " +
                   std::to_string(p.applied) + " in all");
  }
  *point = p;
  return core::Status::Ok();
}

}  // namespace nav::daemon
