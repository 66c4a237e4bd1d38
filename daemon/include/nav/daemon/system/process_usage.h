#pragma once
// Process CPU and memory for navd's health_t, read from
// procfs (proc(5)): utime + stime of /proc/<pid>/stat (fields 14 and 15, clock ticks) and
// VmRSS / VmHWM of /proc/<pid>/status (kB). CPU % is the process CPU time over the wall interval
// between two samples, 100 = one core fully busy (2 busy threads: 200); resolution one clock tick
// (10 ms at USER_HZ 100) per interval, i.e. 1 % over navd's 1 s health period.
// Parsing is separate from reading so it is tested on fixed text. Not thread-safe (one owner,
// the publisher thread); a sample reads two small files into strings (the publisher thread
// allocates, the filter thread never calls this).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace nav::daemon {

struct ProcessUsageSample {
  std::int64_t wall_us = 0;  ///< CLOCK_MONOTONIC when taken
  double cpu_s = 0.0;        ///< utime + stime since the process started
  double rss_mb = 0.0;       ///< VmRSS, MiB (2^20 bytes)
  double peak_rss_mb = 0.0;  ///< VmHWM (resident high-water mark), MiB
};

/// utime + stime in seconds from the text of /proc/<pid>/stat; nullopt when malformed. The
/// command name (field 2, in parentheses) may contain spaces and ')': fields are counted after
/// the LAST ')'.
std::optional<double> parse_proc_stat_cpu_s(std::string_view stat, long ticks_per_s);

/// The value in kB of `key` ("VmRSS", "VmHWM") in the text of /proc/<pid>/status; nullopt
/// when absent or malformed.
std::optional<double> parse_proc_status_kb(std::string_view status, std::string_view key);

/// CPU % over [earlier, later] (100 = one core); 0 when the interval is not positive.
double cpu_percent(const ProcessUsageSample& earlier, const ProcessUsageSample& later);

/// Reads /proc/self: the current sample, or nullopt with `error` saying which file failed.
std::optional<ProcessUsageSample> read_process_usage(std::string* error = nullptr);

/// Keeps the previous sample: each update() gives the CPU % since the last one (the first
/// since the process started is not known: 0).
class ProcessUsageMeter {
 public:
  struct Reading {
    double cpu_percent = 0.0;
    double rss_mb = 0.0;
    double peak_rss_mb = 0.0;
    bool ok = false;  ///< false when /proc could not be read (values 0)
  };
  Reading update();

 private:
  std::optional<ProcessUsageSample> last_;
};

}  // namespace nav::daemon
