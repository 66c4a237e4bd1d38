// NavFilter checkpoints: map sections + the "NAVF" section (checkpoint/nav_filter_checkpoint.h).
#include "nav/daemon/checkpoint/nav_filter_checkpoint.h"

#include <optional>
#include <utility>

#include "nav/core/navigation/nav_filter_serialization.h"
#include "nav/core/serialization/archive.h"
#include "nav/core/serialization/map_codec.h"

namespace nav::daemon {

core::Status add_nav_filter_sections(const NavFilter& filter, core::SectionWriter* writer) {
  if (core::Status s = core::add_map_sections(filter.esdf(), &filter.bounds(), writer); !s.ok()) {
    return s;
  }
  if (core::Status s = core::add_recovery_section(filter.recovery(), writer); !s.ok()) return s;
  return writer->add(kNavFilterSectionTag, kNavFilterSectionVersion, core::to_bytes(filter));
}

core::Status restore_nav_filter(const core::SectionSet& sections, NavFilter* filter) {
  std::optional<core::Esdf> esdf;
  std::optional<core::CovarianceBounds> bounds;
  if (core::Status s = core::restore_map(sections, &esdf, &bounds); !s.ok()) return s;
  if (bounds->options().certify_truncation != filter->bounds().options().certify_truncation) {
    return core::Status::Error(core::StatusCode::kInvalidArgument,
                               "NavFilter checkpoint: bounds certification differs from the "
                               "options");
  }
  core::StateRecovery recovery = filter->recovery();
  if (core::Status s = core::restore_recovery(sections, esdf->num_blocks(), &recovery); !s.ok()) {
    return s;
  }
  const core::SectionView* v = nullptr;
  if (core::Status s = sections.require(kNavFilterSectionTag, kNavFilterSectionVersion, &v);
      !s.ok()) {
    return s;
  }
  NavFilter next(*filter);  // everything restored into a copy: all or nothing
  next.restore_map(std::move(*esdf), std::move(*bounds), std::move(recovery));
  core::ReadArchive ar(v->bytes, "NAVF section", v->offset);
  next.serialize(ar);
  if (core::Status s = ar.finish(); !s.ok()) return s;
  *filter = std::move(next);
  return core::Status::Ok();
}

}  // namespace nav::daemon
