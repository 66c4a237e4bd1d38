#pragma once
// Depth of sea water from pressure: UNESCO 1983 algorithm (N. P. Fofonoff and R. C. Millard Jr.,
// "Algorithms for computation of fundamental properties of seawater", UNESCO Technical Papers
// in Marine Science 44, 1983, section 6 "Depth"), for a standard ocean (0 degC, 35 PSU) with
// the latitude-dependent gravity of the International Formula (1967) and the mean vertical
// gradient of gravity 2.184e-6 m/s^2 per metre (1.092e-6 per decibar of pressure).
// Check value (their table): 10000 dbar at latitude 30 deg -> 9712.653 m.

#include <optional>
#include <string>

namespace nav::drivers {

constexpr double kPascalPerDecibar = 1.0e4;
constexpr double kStandardAtmospherePa = 101325.0;

/// Depth in metres below the sea surface for a sea pressure `sea_pressure_dbar` (absolute
/// pressure minus the atmospheric pressure at the surface, >= 0) at geodetic latitude
/// `latitude_rad`. Pure formula; callers validate the inputs.
double unesco1983_depth_m(double sea_pressure_dbar, double latitude_rad);

struct DepthConversionOptions {
  /// Geodetic latitude of the operating area in radians, [-pi/2, pi/2]. The depth changes by
  /// about 0.5 % between equator and pole.
  double latitude_rad = 0.0;
  /// Atmospheric tare subtracted from an absolute pressure (Pa), e.g. the reading of the
  /// pressure sensor at the surface before the dive; range [0, 2e5]. Use 0 for a gauge sensor.
  double atmospheric_pressure_pa = kStandardAtmospherePa;
  /// Sea pressures below -max_negative_sea_pressure_pa (sensor in air, wrong tare) are
  /// rejected; small negative ones (noise at the surface) give depth 0. Range [0, 1e5].
  double max_negative_sea_pressure_pa = 5.0e3;
  /// Pressures above this (Pa, absolute) are rejected: the deepest ocean is ~1.1e8 Pa.
  double max_pressure_pa = 1.2e8;

  /// Empty when valid, otherwise what is wrong.
  std::string validate() const;
};

/// Depth (m, positive down) from an absolute pressure `pressure_pa` with the tare of
/// `options`; empty when the pressure is not finite or outside the accepted range.
std::optional<double> depth_from_pressure_m(double pressure_pa,
                                            const DepthConversionOptions& options);

}  // namespace nav::drivers
