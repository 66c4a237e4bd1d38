#include "nav/sim/seafloor.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

namespace nav::sim {
namespace {

constexpr double kCoarseStepM = 0.5;  // grid of safe_depth_m

/// A box of debris (or a deck fitting) in the site frame: centre, half sizes, yaw, height.
struct Block {
  double cx_m, cy_m, half_length_m, half_width_m, yaw_rad, height_m;
};

/// Running minimum over a window of +-radius along rows (dx=1) or columns (dx=nx).
void min_filter_1d(std::vector<float>& v, int nx, int ny, int radius, bool along_x) {
  const std::vector<float> in = v;
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      float m = in[static_cast<std::size_t>(iy * nx + ix)];
      for (int k = -radius; k <= radius; ++k) {
        const int jx = along_x ? std::clamp(ix + k, 0, nx - 1) : ix;
        const int jy = along_x ? iy : std::clamp(iy + k, 0, ny - 1);
        m = std::min(m, in[static_cast<std::size_t>(jy * nx + jx)]);
      }
      v[static_cast<std::size_t>(iy * nx + ix)] = m;
    }
  }
}

void box_blur_1d(std::vector<float>& v, int nx, int ny, int radius, bool along_x) {
  const std::vector<float> in = v;
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      double sum = 0.0;
      for (int k = -radius; k <= radius; ++k) {
        const int jx = along_x ? std::clamp(ix + k, 0, nx - 1) : ix;
        const int jy = along_x ? iy : std::clamp(iy + k, 0, ny - 1);
        sum += in[static_cast<std::size_t>(jy * nx + jx)];
      }
      v[static_cast<std::size_t>(iy * nx + ix)] = static_cast<float>(sum / (2 * radius + 1));
    }
  }
}

}  // namespace

double Seafloor::Grid::sample(double x_m, double y_m) const {
  const double fx = std::clamp((x_m - x0_m) / step_m, 0.0, static_cast<double>(nx - 1));
  const double fy = std::clamp((y_m - y0_m) / step_m, 0.0, static_cast<double>(ny - 1));
  const int ix = std::min(static_cast<int>(fx), nx - 2);
  const int iy = std::min(static_cast<int>(fy), ny - 2);
  const double ax = fx - ix, ay = fy - iy;
  auto at = [&](int jx, int jy) {
    return static_cast<double>(values[static_cast<std::size_t>(jy * nx + jx)]);
  };
  return (1 - ay) * ((1 - ax) * at(ix, iy) + ax * at(ix + 1, iy)) +
         ay * ((1 - ax) * at(ix, iy + 1) + ax * at(ix + 1, iy + 1));
}

Seafloor::Seafloor(const GridExtent& extent, double wreck_x_m, double wreck_y_m,
                   const SeafloorOptions& options, std::uint64_t seed)
    : extent_(extent), options_(options), wreck_x_m_(wreck_x_m), wreck_y_m_(wreck_y_m) {
  if (!(options.resolution_m >= 0.01 && options.resolution_m <= 1.0))
    throw std::invalid_argument("SeafloorOptions.resolution_m: " +
                                std::to_string(options.resolution_m) + " outside [0.01, 1] m");
  if (!(extent.x_max_m > extent.x_min_m + 1.0 && extent.y_max_m > extent.y_min_m + 1.0))
    throw std::invalid_argument("GridExtent: empty area");
  nx_ = static_cast<int>(std::ceil((extent.x_max_m - extent.x_min_m) / options.resolution_m)) + 1;
  ny_ = static_cast<int>(std::ceil((extent.y_max_m - extent.y_min_m) / options.resolution_m)) + 1;
  build_relief(seed);
  build_safe_depth();
}

double Seafloor::flat_depth_m(double x_m, double y_m) const {
  const double sx = x_m - wreck_x_m_, sy = y_m - wreck_y_m_;
  double d = options_.mean_depth_m + 0.01 * sx + 0.004 * sy;  // gentle slope, deeper south-east
  for (const Wave& w : waves_) d += w.amplitude_m * std::sin(w.kx * sx + w.ky * sy + w.phase);
  return d;
}

void Seafloor::build_relief(std::uint64_t seed) {
  std::mt19937_64 rng(seed ^ 0x5eaf100dULL);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  auto range = [&](double a, double b) { return a + (b - a) * uni(rng); };
  const double two_pi = 2.0 * std::numbers::pi;
  for (double wavelength_m : {60.0, 23.0, 9.0, 3.5}) {
    const double dir = range(0.0, two_pi), k = two_pi / (wavelength_m * range(0.8, 1.25));
    waves_.push_back(
        {k * std::cos(dir), k * std::sin(dir), range(0.0, two_pi), 0.006 * wavelength_m});
  }

  const SeafloorOptions& o = options_;
  const double half_beam = 0.5 * o.hull_beam_m;
  const double break_phase = range(0.0, two_pi);
  // Deck fittings (site frame): deckhouses on the boat deck, then random winches and davits.
  std::vector<Block> deck = {{-16.0, 0.0, 6.0, 7.0, 0.0, 2.6},
                             {14.0, 0.0, 9.0, 7.5, 0.0, 2.6},
                             {2.0, 0.0, 2.5, 4.0, 0.0, 4.5}};
  for (int i = 0; i < 40; ++i)
    deck.push_back({range(o.break_x_m + 4.0, 60.0), range(-half_beam + 1.0, half_beam - 1.0),
                    range(0.2, 1.0), range(0.2, 0.8), range(0.0, two_pi), range(0.4, 1.4)});
  // Debris field: dense south of the break, sparse elsewhere; then small rocks everywhere.
  std::vector<Block> debris;
  for (int i = 0; i < 260; ++i) {
    const bool near_break = i < 200;
    const double cx =
        near_break ? o.break_x_m - std::abs(range(-1.0, 1.0)) * 35.0 : range(-60.0, 60.0);
    debris.push_back({cx, near_break ? range(-22.0, 22.0) : range(-40.0, 40.0), range(0.2, 2.0),
                      range(0.15, 1.2), range(0.0, two_pi), range(0.15, near_break ? 2.5 : 0.8)});
  }
  for (int i = 0; i < 900; ++i)
    debris.push_back({range(-70.0, 70.0), range(-50.0, 50.0), range(0.05, 0.25), range(0.05, 0.2),
                      range(0.0, two_pi), range(0.05, 0.2)});

  depth_ = {extent_.x_min_m,
            extent_.y_min_m,
            o.resolution_m,
            nx_,
            ny_,
            std::vector<float>(static_cast<std::size_t>(nx_) * ny_)};
  std::vector<float> hull_top(depth_.values.size(), 0.0f);
  for (int iy = 0; iy < ny_; ++iy) {
    const double y = extent_.y_min_m + iy * o.resolution_m, sy = y - wreck_y_m_;
    const double ay = std::abs(sy);
    const double break_here = o.break_x_m + 3.0 * std::sin(0.45 * sy + break_phase);
    for (int ix = 0; ix < nx_; ++ix) {
      const double x = extent_.x_min_m + ix * o.resolution_m, sx = x - wreck_x_m_;
      double h = 0.0;
      if (sx > break_here) {
        const double collapse = std::clamp((sx - break_here) / 8.0, 0.35, 1.0);  // torn decks
        if (ay < half_beam) h = o.hull_height_m * collapse * std::min(1.0, (half_beam - ay) / 0.8);
        if (ay > half_beam - 0.8 && ay < half_beam + 5.0)  // sediment berm pushed up by the hull
          h = std::max(h, 2.0 * (1.0 - std::abs(ay - half_beam) / 5.0));
        if (std::abs(sx - 6.0) < 2.0 && ay < 3.0) h -= 3.0;  // open hatch / funnel casing
      }
      const std::size_t k = static_cast<std::size_t>(iy * nx_ + ix);
      hull_top[k] = static_cast<float>(h);
      depth_.values[k] = static_cast<float>(flat_depth_m(x, y) - h);
    }
  }
  auto stamp = [&](const Block& b, bool on_deck) {
    const double c = std::cos(b.yaw_rad), s = std::sin(b.yaw_rad);
    const double r = std::hypot(b.half_length_m, b.half_width_m);
    const int ix0 =
        std::max(0, static_cast<int>((wreck_x_m_ + b.cx_m - r - extent_.x_min_m) / o.resolution_m));
    const int ix1 = std::min(
        nx_ - 1,
        static_cast<int>((wreck_x_m_ + b.cx_m + r - extent_.x_min_m) / o.resolution_m) + 1);
    const int iy0 =
        std::max(0, static_cast<int>((wreck_y_m_ + b.cy_m - r - extent_.y_min_m) / o.resolution_m));
    const int iy1 = std::min(
        ny_ - 1,
        static_cast<int>((wreck_y_m_ + b.cy_m + r - extent_.y_min_m) / o.resolution_m) + 1);
    for (int iy = iy0; iy <= iy1; ++iy) {
      for (int ix = ix0; ix <= ix1; ++ix) {
        const double dx = extent_.x_min_m + ix * o.resolution_m - wreck_x_m_ - b.cx_m;
        const double dy = extent_.y_min_m + iy * o.resolution_m - wreck_y_m_ - b.cy_m;
        const double along = c * dx + s * dy, across = -s * dx + c * dy;
        if (std::abs(along) > b.half_length_m || std::abs(across) > b.half_width_m) continue;
        const std::size_t k = static_cast<std::size_t>(iy * nx_ + ix);
        if (on_deck && hull_top[k] < 0.5 * o.hull_height_m) continue;  // fittings stay on deck
        depth_.values[k] -= static_cast<float>(b.height_m);            // stacked debris piles up
      }
    }
  };
  for (const Block& b : deck) stamp(b, true);
  for (const Block& b : debris) stamp(b, false);
}

void Seafloor::build_safe_depth() {
  const int f = std::max(1, static_cast<int>(std::lround(kCoarseStepM / options_.resolution_m)));
  const int cnx = (nx_ + f - 1) / f, cny = (ny_ + f - 1) / f;
  safe_ = {extent_.x_min_m,
           extent_.y_min_m,
           f * options_.resolution_m,
           cnx,
           cny,
           std::vector<float>(static_cast<std::size_t>(cnx) * cny, 1e9f)};
  for (int iy = 0; iy < ny_; ++iy)
    for (int ix = 0; ix < nx_; ++ix) {
      float& c = safe_.values[static_cast<std::size_t>((iy / f) * cnx + ix / f)];
      c = std::min(c, depth_.values[static_cast<std::size_t>(iy * nx_ + ix)]);
    }
  const int radius = static_cast<int>(std::ceil(options_.clearance_radius_m / safe_.step_m));
  min_filter_1d(safe_.values, cnx, cny, radius, true);
  min_filter_1d(safe_.values, cnx, cny, radius, false);
  const int blur = static_cast<int>(std::ceil(1.5 / safe_.step_m));
  box_blur_1d(safe_.values, cnx, cny, blur, true);
  box_blur_1d(safe_.values, cnx, cny, blur, false);
}

double Seafloor::depth_m(double x_m, double y_m) const { return depth_.sample(x_m, y_m); }
double Seafloor::safe_depth_m(double x_m, double y_m) const { return safe_.sample(x_m, y_m); }
double Seafloor::relief_height_m(double x_m, double y_m) const {
  return flat_depth_m(x_m, y_m) - depth_m(x_m, y_m);
}

}  // namespace nav::sim
