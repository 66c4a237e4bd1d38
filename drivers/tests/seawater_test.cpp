// UNESCO 1983 depth from pressure: the published check value, physical sanity (hydrostatics,
// monotonicity, latitude effect) and the tare/range handling of depth_from_pressure_m.
#include "nav/drivers/codecs/seawater.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace nav::drivers {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(Seawater, PublishedCheckValue) {
  // Fofonoff & Millard (1983), UNESCO Tech. Pap. Mar. Sci. 44, p. 28: 10000 dbar, 30 deg.
  EXPECT_NEAR(unesco1983_depth_m(10000.0, 30.0 * kDeg), 9712.653, 5e-4);
}

TEST(Seawater, HydrostaticLimitNearTheSurface) {
  // Near the surface depth ~ p / (rho g) with the standard ocean's density 1028.1 kg/m^3
  // (35 PSU, 0 degC, 0 dbar) and normal gravity 9.780318 m/s^2 at the equator.
  const double p_dbar = 1.0;
  const double expected_m = p_dbar * 1.0e4 / (1028.106 * 9.780318);
  EXPECT_NEAR(unesco1983_depth_m(p_dbar, 0.0), expected_m, 1e-4);
  EXPECT_DOUBLE_EQ(unesco1983_depth_m(0.0, 0.7), 0.0);
}

TEST(Seawater, MonotonicInPressureAndShallowerTowardsThePoles) {
  double previous = -1.0;
  for (double p = 0.0; p <= 11000.0; p += 250.0) {
    const double z = unesco1983_depth_m(p, 45.0 * kDeg);
    EXPECT_GT(z, previous);
    previous = z;
  }
  // Gravity grows with latitude: the same pressure is reached at a smaller depth; the
  // equator-to-pole difference is about 0.53 % (ratio of normal gravities).
  const double equator = unesco1983_depth_m(5000.0, 0.0);
  const double pole = unesco1983_depth_m(5000.0, 90.0 * kDeg);
  EXPECT_LT(pole, equator);
  EXPECT_NEAR(equator / pole, 9.832186 / 9.780318, 2e-4);
  EXPECT_DOUBLE_EQ(unesco1983_depth_m(5000.0, -30.0 * kDeg),
                   unesco1983_depth_m(5000.0, 30.0 * kDeg));
}

TEST(Seawater, DepthFromAbsolutePressureWithTare) {
  DepthConversionOptions options;
  options.latitude_rad = 30.0 * kDeg;
  options.atmospheric_pressure_pa = 101325.0;
  const auto z = depth_from_pressure_m(101325.0 + 1.0e8, options);
  ASSERT_TRUE(z.has_value());
  EXPECT_NEAR(*z, 9712.653, 5e-4);
  // At the surface and slightly below the tare (sensor noise): zero depth.
  EXPECT_DOUBLE_EQ(*depth_from_pressure_m(101325.0, options), 0.0);
  EXPECT_DOUBLE_EQ(*depth_from_pressure_m(101000.0, options), 0.0);
  // Far below the tare (in air at altitude, wrong tare), absurd, or not a number: rejected.
  EXPECT_FALSE(depth_from_pressure_m(50000.0, options).has_value());
  EXPECT_FALSE(depth_from_pressure_m(5.0e8, options).has_value());
  EXPECT_FALSE(depth_from_pressure_m(std::nan(""), options).has_value());
  // A gauge sensor: no tare.
  options.atmospheric_pressure_pa = 0.0;
  EXPECT_NEAR(*depth_from_pressure_m(1.0e8, options), 9712.653, 5e-4);
}

TEST(Seawater, OptionsValidate) {
  EXPECT_EQ(DepthConversionOptions{}.validate(), "");
  DepthConversionOptions bad;
  bad.latitude_rad = 2.0;
  EXPECT_NE(bad.validate().find("latitude_rad"), std::string::npos);
  bad = DepthConversionOptions{};
  bad.atmospheric_pressure_pa = -1.0;
  EXPECT_NE(bad.validate().find("atmospheric_pressure_pa"), std::string::npos);
}

}  // namespace
}  // namespace nav::drivers
