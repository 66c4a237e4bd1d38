// GPIO trigger/strobe: strobe edge pairing into exposure pulses (hand-made edge sequences with
// missed edges, stuck lines and clock steps), the in-memory loopback, options validation, and
// the libgpiod implementation where a /dev/gpiochip* exists (skipped with the reason otherwise).

#include "nav/drivers/transports/gpio_lines.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

namespace nav::drivers {
namespace {

using namespace std::chrono_literals;

EdgeEvent edge(bool rising, int64_t t_us) { return EdgeEvent{rising, t_us, {}}; }

TEST(StrobePulseDecoder, PairsRisingAndFallingIntoExposureMidpoints) {
  StrobePulseDecoder d;
  EXPECT_FALSE(d.feed(edge(true, 1'000)).has_value());
  const auto p = d.feed(edge(false, 3'000));  // 2 ms exposure
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->start_us, 1'000);
  EXPECT_EQ(p->width_us(), 2'000);
  EXPECT_EQ(p->mid_us(), 2'000);
  EXPECT_EQ(d.stats().pulses, 1u);
}

TEST(StrobePulseDecoder, MissedEdgesAreCountedNotMispaired) {
  StrobePulseDecoder d;
  d.feed(edge(true, 1'000));
  d.feed(edge(true, 9'000));  // falling edge of the first pulse lost
  const auto p = d.feed(edge(false, 10'000));
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->start_us, 9'000);                          // paired with the latest rising edge only
  EXPECT_FALSE(d.feed(edge(false, 11'000)).has_value());  // falling without rising
  EXPECT_EQ(d.stats().orphan_edges, 2u);
  EXPECT_EQ(d.stats().pulses, 1u);
}

TEST(StrobePulseDecoder, StuckLineAndClockStepsAreRejected) {
  StrobePulseDecoder d(50'000);  // exposures never exceed 50 ms
  d.feed(edge(true, 0));
  EXPECT_FALSE(d.feed(edge(false, 200'000)).has_value());
  EXPECT_EQ(d.stats().too_long, 1u);
  d.feed(edge(true, 300'000));
  EXPECT_FALSE(d.feed(edge(false, 299'000)).has_value());  // older than the previous edge
  EXPECT_EQ(d.stats().out_of_order, 1u);
  d.feed(edge(true, 400'000));
  EXPECT_TRUE(d.feed(edge(false, 401'000)).has_value());  // recovers
}

TEST(LoopbackGpio, TriggerPulseComesBackAsTimedEdges) {
  LoopbackGpio gpio;
  StrobePulseDecoder decoder;
  std::optional<StrobePulse> pulse;
  std::thread reader([&] {
    EdgeEvent e;
    while (!pulse && gpio.wait_edge(e, 2s).ok()) pulse = decoder.feed(e);
  });
  ASSERT_TRUE(gpio.pulse(2000us).ok());
  reader.join();
  ASSERT_TRUE(pulse.has_value());
  EXPECT_GE(pulse->width_us(), 2000);
  EXPECT_LT(pulse->width_us(), 1'000'000);
  EXPECT_TRUE(gpio.set(false).ok());  // already inactive: no new edge
  EdgeEvent e;
  EXPECT_EQ(gpio.wait_edge(e, 10ms).code(), IoCode::kTimeout);
  EXPECT_EQ(gpio.pulse(0us).code(), IoCode::kInvalidArgument);
}

TEST(GpioOptions, ValidateNamesTheBadField) {
  GpioOptions o;
  EXPECT_FALSE(o.validate().ok());  // no line configured
  o.trigger_line = 3;
  EXPECT_TRUE(o.validate().ok());
  o.strobe_line = 3;
  EXPECT_NE(o.validate().message().find("trigger_line equals strobe_line"), std::string::npos);
  o.strobe_line = -5;
  EXPECT_FALSE(o.validate().ok());
}

TEST(GpioLines, MissingChipIsReportedWithItsPath) {
  GpioOptions o;
  o.chip = "/dev/gpiochip-navd-missing";
  o.trigger_line = 0;
  GpioLines lines(o);
  const IoStatus s = lines.open();
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find(o.chip), std::string::npos) << s.message();
  EXPECT_EQ(lines.set(true).code(), IoCode::kInvalidArgument);  // nothing open: refused
  EdgeEvent e;
  EXPECT_EQ(lines.wait_edge(e, 1ms).code(), IoCode::kInvalidArgument);
}

TEST(GpioLines, DrivesAndReadsARealChip) {
  const char* env = std::getenv("NAV_GPIO_CHIP");
  const std::string chip = env != nullptr ? env : "/dev/gpiochip0";
  if (!std::filesystem::exists(chip))
    GTEST_SKIP() << "no GPIO chip " << chip << " on this machine (set NAV_GPIO_CHIP)";
  GpioOptions o;
  o.chip = chip;
  o.trigger_line = 0;
  o.strobe_line = 1;
  GpioLines lines(o);
  const IoStatus s = lines.open();
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(lines.pulse(100us).ok());
}

}  // namespace
}  // namespace nav::drivers
