// libFuzzer target for the checkpoint payload decoder behind the CRC (checkpoint.h: a file
// whose CRC-32s verify may still carry any payload, e.g. written by another build or damaged
// before the checksum was taken): core::SectionSet::decode, then restore_nav_filter into a
// NavFilter built from config/sim.yaml's options and restore_resume_point, as
// resume_nav_filter() does. Every outcome must be a Status; on error the filter must be left
// unchanged (still uninitialised), never crash or throw. Seeds: checkpoint payloads written by
// fuzz_seeds (seeds.cpp) from a short synthetic dive.
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <span>

#include "nav/core/serialization/sections.h"
#include "nav/daemon/checkpoint/nav_filter_checkpoint.h"
#include "nav/daemon/checkpoint/resume_point.h"
#include "nav/daemon/config/config.h"

namespace {

const nav::daemon::NavFilterOptions& options() {
  static const nav::daemon::NavFilterOptions o = nav::daemon::filter_options_from_config(
      nav::daemon::load_config_file(NAV_SOURCE_DIR "/config/sim.yaml"));
  return o;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  nav::core::SectionSet sections;
  if (!nav::core::SectionSet::decode(std::span(bytes, size), &sections).ok()) return 0;
  nav::daemon::NavFilter filter(options(), nullptr);
  const nav::core::Status restored = nav::daemon::restore_nav_filter(sections, &filter);
  if (!restored.ok() && filter.initialised()) std::abort();  // all or nothing
  nav::daemon::ResumePoint point;
  (void)nav::daemon::restore_resume_point(sections, &point);
  return 0;
}
