#include "navd/summary.h"

#include <spdlog/fmt/fmt.h>

namespace nav::navd {
namespace {

/// JSON string literal (quotes, backslashes and control characters escaped).
std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt::format("\\u{:04x}", static_cast<int>(c));
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace

std::string summary_json(const Summary& s) {
  const FilterCounters& c = s.filter.counters;
  const double rtf = s.wall_s > 0.0 ? s.filter.survey_time_s / s.wall_s : 0.0;
  const double mean_recovery_ms =
      s.recovery.solves > 0 ? 1e3 * s.recovery.total_solve_s / s.recovery.solves : 0.0;
  std::string j = "{";
  j += fmt::format("\"completed\":{},\"images\":{},\"camera_links\":{},\"steps\":{},",
                   s.filter.completed, c.images, c.camera_links, c.steps);
  j += fmt::format("\"survey_images\":{},\"survey_links\":{},\"survey_steps\":{},",
                   s.survey.options.num_images, s.survey.num_links, s.survey.steps.size());
  j += fmt::format("\"updates\":{},\"update_failures\":{},", c.updates, c.update_failures);
  j += fmt::format("\"final_position_error_m\":{:.6g},\"final_position_error_running_m\":{:.6g},",
                   s.filter.final_position_error_m, s.filter.final_position_error_running_m);
  j += fmt::format("\"survey_time_s\":{:.6g},\"wall_s\":{:.6g},\"realtime_factor\":{:.6g},",
                   s.filter.survey_time_s, s.wall_s, rtf);
  j += fmt::format("\"queue_drops\":{},\"late_drops\":{},\"full_drops\":{},", s.queue_drops,
                   s.filter.ordering.dropped_late, s.filter.ordering.dropped_full);
  j += fmt::format("\"unmatched_measurements\":{},", c.unmatched_measurements);
  j += fmt::format("\"recovery_idle_refinements\":{},", s.recovery.idle_refinements);
  j += fmt::format("\"recoveries\":{},\"recoveries_applied\":{},\"recovery_failures\":{},",
                   s.recovery.solves, c.recoveries_applied, s.recovery.failures);
  j += fmt::format("\"cg_relative_residual\":{:.6g},\"cg_mean_relative_residual\":{:.6g},",
                   s.recovery.last_relative_residual, s.recovery.last_mean_relative_residual);
  j += fmt::format("\"mean_recovery_ms\":{:.6g},\"published_position_sigma_m\":{:.6g},",
                   mean_recovery_ms, s.published_position_sigma_m);
  j += fmt::format("\"solutions_published\":{},\"health_published\":{},\"publish_failures\":{},",
                   s.publisher.solutions, s.publisher.health, s.publisher.failures);
  j += fmt::format("\"error\":{}", quoted(s.filter.error));
  return j + "}";
}

}  // namespace nav::navd
