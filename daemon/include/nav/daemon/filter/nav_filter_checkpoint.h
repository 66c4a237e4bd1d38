#pragma once
// Checkpoints of the NavFilter (issue "navd" §6): the map sections of core/serialization
// (ESDF, BNDS, RCVY) plus the "NAVF" section with everything else the filter carries between
// measurements, so that a filter restored from a checkpoint and fed the same further
// measurements stays bit-identical to the original:
//   initialisation state (seen attitude/heading/depth, measurements held until initialisation),
//   time and newest validity, the warm-start extension since the
//   last recovery (A, P_robot, Σ_tt, flags, kept block), the pending image and its links, the
//   altitude in use, block -> image map, image records (trajectory), link history, proposal
//   records, counters, each attitude sensor's last angles (SensorModels), and the recovery
//   thread's job in flight, AWAITED: encoding waits for the job and stores its result and
//   hand-off time, so that the resumed filter takes the same result at the same data time as
//   the uninterrupted one (a checkpoint may be taken at any measurement; the wait is at most
//   one job of fixed iterations). A filter resumed with the thread off drops that result.
// Section "NAVF", version 3 (v2: held measurements, newest validity, link z/R/innovation,
// images' initial bounds; v3: the recovery job), little-endian (core/serialization/byte_io.h);
// the layout is the order of the fields in nav_filter_checkpoint.cpp's encode(). Decoding checks every count
// against the bytes present, every index against the filter (blocks, images, links, sensors).
// The filter to restore into is built from the same config and options first (they are not in
// the checkpoint: a changed config takes effect on resume); on error it is left unchanged.

#include <cstdint>

#include "nav/core/serialization/sections.h"
#include "nav/core/status.h"
#include "nav/daemon/filter/nav_filter.h"

namespace nav::daemon {

inline constexpr std::uint32_t kNavFilterSectionTag = core::section_tag("NAVF");
inline constexpr std::uint32_t kNavFilterSectionVersion = 3;

/// Adds the ESDF, BNDS, RCVY and NAVF sections.
core::Status add_nav_filter_sections(const NavFilter& filter, core::SectionWriter* writer);

/// Restores `filter` (built from the checkpoint's config) from the sections, all or nothing.
core::Status restore_nav_filter(const core::SectionSet& sections, NavFilter* filter);

}  // namespace nav::daemon
