// ProcessUsage: procfs parsing on fixed text (proc(5) layouts), the CPU % arithmetic, and the
// real /proc/self readings against what the test itself did (CPU burnt, memory touched).
#include "nav/daemon/system/process_usage.h"

#include <gtest/gtest.h>

#include <ctime>
#include <vector>

namespace nav::daemon {
namespace {

// A real /proc/<pid>/stat line whose command name contains spaces and ')'.
constexpr const char* kStat =
    "4242 (nav d) (x)) S 1 4242 4242 0 -1 4194560 1234 0 5 0 250 75 0 0 20 0 7 0 "
    "123456 104857600 25600 18446744073709551615 1 1 0 0 0 0 0 4096 0 0 0 0 17 1 0 0 0 0 0";

constexpr const char* kStatus =
    "Name:\tnavd\nUmask:\t0022\nState:\tS (sleeping)\nVmPeak:\t  600000 kB\n"
    "VmHWM:\t  370688 kB\nVmRSS:\t  102400 kB\nThreads:\t7\n";

double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

TEST(ProcessUsage, StatGivesUtimePlusStimeInSecondsAfterTheLastParenthesis) {
  const std::optional<double> cpu = parse_proc_stat_cpu_s(kStat, 100);
  ASSERT_TRUE(cpu.has_value());
  EXPECT_DOUBLE_EQ(*cpu, (250.0 + 75.0) / 100.0);
}

TEST(ProcessUsage, MalformedStatIsRejected) {
  EXPECT_FALSE(parse_proc_stat_cpu_s("4242 navd S 1 2 3", 100).has_value());
  EXPECT_FALSE(parse_proc_stat_cpu_s("4242 (navd) S 1 2 3", 100).has_value());
  EXPECT_FALSE(parse_proc_stat_cpu_s(kStat, 0).has_value());
}

TEST(ProcessUsage, StatusGivesRssAndHighWaterMarkInKb) {
  EXPECT_EQ(parse_proc_status_kb(kStatus, "VmRSS"), 102400.0);
  EXPECT_EQ(parse_proc_status_kb(kStatus, "VmHWM"), 370688.0);
  EXPECT_FALSE(parse_proc_status_kb(kStatus, "VmSwap").has_value());
  EXPECT_FALSE(parse_proc_status_kb("VmRSS:\t kB\n", "VmRSS").has_value());
}

TEST(ProcessUsage, CpuPercentIsCpuTimeOverWallTimeWithOneCoreAtHundred) {
  ProcessUsageSample a, b;
  a.wall_us = 1'000'000;
  a.cpu_s = 10.0;
  b.wall_us = 3'000'000;  // 2 s later
  b.cpu_s = 13.0;         // 3 s of CPU: 1.5 cores
  EXPECT_DOUBLE_EQ(cpu_percent(a, b), 150.0);
  EXPECT_EQ(cpu_percent(b, a), 0.0);  // not a positive interval
}

TEST(ProcessUsage, SelfReadingCountsTheCpuThisTestBurns) {
  std::string error;
  const std::optional<ProcessUsageSample> before = read_process_usage(&error);
  ASSERT_TRUE(before.has_value()) << error;
  const double start = process_cpu_s();
  volatile double sink = 0.0;
  while (process_cpu_s() - start < 0.3) sink = sink + 1.0;
  const std::optional<ProcessUsageSample> after = read_process_usage(&error);
  ASSERT_TRUE(after.has_value()) << error;
  // procfs counts in clock ticks (10 ms at 100 Hz): allow two ticks of truncation.
  EXPECT_GE(after->cpu_s - before->cpu_s, 0.3 - 0.02);
  EXPECT_GT(cpu_percent(*before, *after), 0.0);
}

TEST(ProcessUsage, SelfReadingSeesTouchedMemoryAndAPeakAtLeastTheCurrentRss) {
  const std::optional<ProcessUsageSample> before = read_process_usage();
  ASSERT_TRUE(before.has_value());
  std::vector<char> block(64u << 20);
  for (std::size_t i = 0; i < block.size(); i += 4096) block[i] = 1;  // touch every page
  const std::optional<ProcessUsageSample> during = read_process_usage();
  ASSERT_TRUE(during.has_value());
  EXPECT_GE(during->rss_mb - before->rss_mb, 60.0);
  EXPECT_GE(during->peak_rss_mb, during->rss_mb);
  block = {};
  block.shrink_to_fit();
  const std::optional<ProcessUsageSample> after = read_process_usage();
  ASSERT_TRUE(after.has_value());
  // The high-water mark keeps the block (the kernel's RSS counters are batched per thread, so
  // compare with a margin rather than with `during` exactly).
  EXPECT_GE(after->peak_rss_mb - before->rss_mb, 60.0);
}

TEST(ProcessUsage, MeterGivesNoCpuOnTheFirstReadingThenAPositiveOne) {
  ProcessUsageMeter meter;
  const ProcessUsageMeter::Reading first = meter.update();
  ASSERT_TRUE(first.ok);
  EXPECT_EQ(first.cpu_percent, 0.0);
  EXPECT_GT(first.rss_mb, 0.0);
  const double start = process_cpu_s();
  volatile double sink = 0.0;
  while (process_cpu_s() - start < 0.05) sink = sink + 1.0;
  const ProcessUsageMeter::Reading second = meter.update();
  ASSERT_TRUE(second.ok);
  EXPECT_GT(second.cpu_percent, 0.0);
}

}  // namespace
}  // namespace nav::daemon
