// navd's NavFilter checkpointing: resume, periodic and shutdown checkpoints
// (filter/nav_filter_checkpointer.h).
#include "nav/daemon/checkpoint/nav_filter_checkpointer.h"

#include <utility>

#include "nav/core/serialization/sections.h"
#include "nav/daemon/checkpoint/nav_filter_checkpoint.h"

namespace nav::daemon {

ResumedNavFilter resume_nav_filter(const std::filesystem::path& dir,
                                   const std::function<std::unique_ptr<NavFilter>()>& make,
                                   const std::string& identity) {
  ResumedNavFilter out;
  const LoadResult loaded = load_newest_valid(dir, [&](const Checkpoint& c) -> std::string {
    if (c.payload_version != kNavFilterPayloadVersion) {
      return "payload version " + std::to_string(c.payload_version) + ", this navd reads " +
             std::to_string(kNavFilterPayloadVersion);
    }
    core::SectionSet sections;
    if (core::Status s = core::SectionSet::decode(c.payload, &sections); !s.ok()) {
      return s.to_string();
    }
    const core::SectionView* id = sections.find(kInputIdentitySectionTag);
    const std::string stored = id ? std::string(id->bytes.begin(), id->bytes.end()) : "";
    if (stored != identity) {
      return "checkpoint of another input ('" + stored + "', this run: '" + identity + "')";
    }
    std::unique_ptr<NavFilter> filter = make();
    ResumePoint point;
    if (core::Status s = restore_nav_filter(sections, filter.get()); !s.ok()) return s.to_string();
    if (core::Status s = restore_resume_point(sections, &point); !s.ok()) return s.to_string();
    out.filter = std::move(filter);
    out.point = point;
    return "";
  });
  if (loaded.checkpoint) out.path = loaded.checkpoint->path;
  out.skipped = loaded.skipped;
  return out;
}

std::vector<std::uint8_t> nav_filter_payload(const NavFilter& filter, const ResumePoint& point,
                                             const std::string& identity) {
  core::SectionWriter writer;
  // Adding fixed, distinct tags cannot fail.
  (void)add_nav_filter_sections(filter, &writer);
  (void)add_resume_section(point, &writer);
  const auto* id = reinterpret_cast<const std::uint8_t*>(identity.data());
  (void)writer.add(kInputIdentitySectionTag, 1, std::span(id, identity.size()));
  return writer.finish();
}

NavFilterCheckpointer::NavFilterCheckpointer(const CheckpointConfig& config, ResumePoint start,
                                             std::string identity)
    : period_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(config.period_s))),
      last_(std::chrono::steady_clock::now()),
      tracker_(start),
      identity_(std::move(identity)),
      worker_(config.path, config.keep) {}

void NavFilterCheckpointer::after_measurement(const NavFilter& filter, const Measurement& m) {
  tracker_.applied(m);
  const auto now = std::chrono::steady_clock::now();
  if (now - last_ < period_) return;
  last_ = now;
  worker_.offer(kNavFilterPayloadVersion, nav_filter_payload(filter, tracker_.point(), identity_));
}

void NavFilterCheckpointer::shutdown(const NavFilter& filter) {
  worker_.offer(kNavFilterPayloadVersion, nav_filter_payload(filter, tracker_.point(), identity_));
  worker_.stop();
}

}  // namespace nav::daemon
