#pragma once
// Checkpoints of the NavFilter: the map sections of core/serialization (ESDF, BNDS, RCVY) plus
// the "NAVF" section with everything else the filter carries between measurements
// (NavFilter::serialize, nav/core/navigation/nav_filter_serialization.h), so that a filter
// restored from a checkpoint and fed the same further measurements stays bit-identical to the
// original. A recovery job in flight is stored awaited (encoding waits for it; at most one job
// of fixed iterations).
// Section "NAVF", version 6 (history: docs/consistency.md "Checkpoint section NAVF versions"),
// little-endian. Decoding checks every count against the bytes present and
// every index against the filter (blocks, images, links, sensors). The filter to restore into
// is built from the same options first (they are not in the checkpoint: a changed config takes
// effect on resume); on error it is left unchanged.

#include <cstdint>

#include "nav/core/serialization/sections.h"
#include "nav/core/status.h"
#include "nav/daemon/filter/filter_options.h"

namespace nav::daemon {

inline constexpr std::uint32_t kNavFilterSectionTag = core::section_tag("NAVF");
inline constexpr std::uint32_t kNavFilterSectionVersion = 6;

/// Adds the ESDF, BNDS, RCVY and NAVF sections.
core::Status add_nav_filter_sections(const NavFilter& filter, core::SectionWriter* writer);

/// Restores `filter` (built from the checkpoint's options) from the sections, all or nothing.
core::Status restore_nav_filter(const core::SectionSet& sections, NavFilter* filter);

}  // namespace nav::daemon
