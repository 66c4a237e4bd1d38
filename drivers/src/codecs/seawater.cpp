// UNESCO 1983 depth from pressure (Fofonoff & Millard 1983, UNESCO Tech. Pap. Mar. Sci. 44,
// section 6). The polynomial is the integral of the specific volume of the standard ocean.
#include "nav/drivers/codecs/seawater.h"

#include <cmath>
#include <numbers>

namespace nav::drivers {

double unesco1983_depth_m(double sea_pressure_dbar, double latitude_rad) {
  const double p = sea_pressure_dbar;
  const double x = std::pow(std::sin(latitude_rad), 2.0);
  // Gravity at the surface (International Formula 1967) plus its mean vertical gradient,
  // expressed per decibar: 2.184e-6 / 2 per metre -> 1.092e-6 per dbar.
  const double gravity_mps2 = 9.780318 * (1.0 + (5.2788e-3 + 2.36e-5 * x) * x) + 1.092e-6 * p;
  const double integral = (((-1.82e-15 * p + 2.279e-10) * p - 2.2512e-5) * p + 9.72659) * p;
  return integral / gravity_mps2;
}

std::string DepthConversionOptions::validate() const {
  if (!(std::abs(latitude_rad) <= std::numbers::pi / 2.0)) {
    return "DepthConversionOptions.latitude_rad outside [-pi/2, pi/2]";
  }
  if (!(atmospheric_pressure_pa >= 0.0 && atmospheric_pressure_pa <= 2.0e5)) {
    return "DepthConversionOptions.atmospheric_pressure_pa outside [0, 2e5] Pa";
  }
  if (!(max_negative_sea_pressure_pa >= 0.0 && max_negative_sea_pressure_pa <= 1.0e5)) {
    return "DepthConversionOptions.max_negative_sea_pressure_pa outside [0, 1e5] Pa";
  }
  if (!(max_pressure_pa > atmospheric_pressure_pa && max_pressure_pa <= 2.0e8)) {
    return "DepthConversionOptions.max_pressure_pa outside (atmospheric_pressure_pa, 2e8] Pa";
  }
  return {};
}

std::optional<double> depth_from_pressure_m(double pressure_pa,
                                            const DepthConversionOptions& options) {
  if (!std::isfinite(pressure_pa) || pressure_pa > options.max_pressure_pa) return std::nullopt;
  const double sea_pressure_pa = pressure_pa - options.atmospheric_pressure_pa;
  if (sea_pressure_pa < -options.max_negative_sea_pressure_pa) return std::nullopt;
  if (sea_pressure_pa <= 0.0) return 0.0;
  return unesco1983_depth_m(sea_pressure_pa / kPascalPerDecibar, options.latitude_rad);
}

}  // namespace nav::drivers
