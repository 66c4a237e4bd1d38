// Process CPU and memory from procfs (process_usage.h, proc(5)).
#include "nav/daemon/system/process_usage.h"

#include <unistd.h>

#include <charconv>
#include <ctime>
#include <fstream>
#include <sstream>

#include "nav/daemon/system/host_clock.h"

namespace nav::daemon {
namespace {

constexpr double kKbPerMb = 1024.0;

/// Skips `n` space-separated fields of `s` from `pos`; npos if there are fewer.
std::size_t skip_fields(std::string_view s, std::size_t pos, int n) {
  for (int i = 0; i < n && pos != std::string_view::npos; ++i) {
    pos = s.find_first_not_of(' ', pos);
    if (pos == std::string_view::npos) return pos;
    pos = s.find(' ', pos);
  }
  return pos == std::string_view::npos ? pos : s.find_first_not_of(' ', pos);
}

std::optional<std::uint64_t> parse_u64(std::string_view s, std::size_t pos) {
  if (pos == std::string_view::npos) return std::nullopt;
  std::uint64_t value = 0;
  const char* end = s.data() + s.size();
  const auto [ptr, ec] = std::from_chars(s.data() + pos, end, value);
  if (ec != std::errc() || (ptr != end && *ptr != ' ' && *ptr != '\n')) return std::nullopt;
  return value;
}

std::optional<std::string> read_file(const char* path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

std::optional<double> parse_proc_stat_cpu_s(std::string_view stat, long ticks_per_s) {
  if (ticks_per_s <= 0) return std::nullopt;
  const std::size_t paren = stat.rfind(')');
  if (paren == std::string_view::npos) return std::nullopt;
  // After "pid (comm)": field 3 (state) is the first; utime and stime are fields 14 and 15.
  const std::size_t utime_pos = skip_fields(stat, paren + 1, 11);
  const std::optional<std::uint64_t> utime = parse_u64(stat, utime_pos);
  const std::optional<std::uint64_t> stime = parse_u64(stat, skip_fields(stat, utime_pos, 1));
  if (!utime || !stime) return std::nullopt;
  return static_cast<double>(*utime + *stime) / static_cast<double>(ticks_per_s);
}

std::optional<double> parse_proc_status_kb(std::string_view status, std::string_view key) {
  std::size_t line = 0;
  while (line < status.size()) {
    const std::size_t end = std::min(status.find('\n', line), status.size());
    const std::string_view text = status.substr(line, end - line);
    if (text.size() > key.size() && text.substr(0, key.size()) == key && text[key.size()] == ':') {
      const std::size_t pos = text.find_first_not_of(" \t", key.size() + 1);
      if (pos == std::string_view::npos) return std::nullopt;
      std::uint64_t kb = 0;
      const auto [ptr, ec] = std::from_chars(text.data() + pos, text.data() + text.size(), kb);
      if (ec != std::errc() || ptr == text.data() + pos) return std::nullopt;
      return static_cast<double>(kb);
    }
    line = end + 1;
  }
  return std::nullopt;
}

double cpu_percent(const ProcessUsageSample& earlier, const ProcessUsageSample& later) {
  const std::int64_t wall_us = later.wall_us - earlier.wall_us;
  if (wall_us <= 0) return 0.0;
  return 100.0 * (later.cpu_s - earlier.cpu_s) / (static_cast<double>(wall_us) * 1e-6);
}

std::optional<ProcessUsageSample> read_process_usage(std::string* error) {
  auto fail = [&](const std::string& why) -> std::optional<ProcessUsageSample> {
    if (error) *error = why;
    return std::nullopt;
  };
  ProcessUsageSample sample;
  sample.wall_us = monotonic_us();
  const std::optional<std::string> stat = read_file("/proc/self/stat");
  if (!stat) return fail("/proc/self/stat: cannot read");
  const std::optional<double> cpu = parse_proc_stat_cpu_s(*stat, sysconf(_SC_CLK_TCK));
  if (!cpu) return fail("/proc/self/stat: no utime/stime in '" + *stat + "'");
  sample.cpu_s = *cpu;
  const std::optional<std::string> status = read_file("/proc/self/status");
  if (!status) return fail("/proc/self/status: cannot read");
  const std::optional<double> rss = parse_proc_status_kb(*status, "VmRSS");
  const std::optional<double> hwm = parse_proc_status_kb(*status, "VmHWM");
  if (!rss || !hwm) return fail("/proc/self/status: no VmRSS or VmHWM line");
  sample.rss_mb = *rss / kKbPerMb;
  sample.peak_rss_mb = *hwm / kKbPerMb;
  return sample;
}

ProcessUsageMeter::Reading ProcessUsageMeter::update() {
  const std::optional<ProcessUsageSample> now = read_process_usage();
  if (!now) return {};
  Reading r;
  r.ok = true;
  r.rss_mb = now->rss_mb;
  r.peak_rss_mb = now->peak_rss_mb;
  if (last_) r.cpu_percent = cpu_percent(*last_, *now);
  last_ = now;
  return r;
}

}  // namespace nav::daemon
