// Pose-constrained correspondence search (pccs.h): search regions from the linearised point
// transfer over the depth interval, a bucket grid of image j's points, and the ratio + mutual
// matching restricted to the regions.

#include "nav/vision/pccs.h"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/core/hal/hal.hpp>
#include <sstream>
#include <stdexcept>

#include "nav/core/geometry/rotation.h"

namespace nav::vision {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// k with P(|N(0,1)| <= k) = p, i.e. erfc(k / sqrt(2)) = 1 - p, by bisection (monotone).
double two_sided_normal_quantile(double p) {
  double lo = 0.0, hi = 40.0;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (std::erfc(mid / std::sqrt(2.0)) > 1.0 - p)
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}

/// Squared Mahalanobis distance (metric M) from q to the segment [a, b].
double segment_distance2(const Eigen::Vector2d& q, const Eigen::Vector2d& a,
                         const Eigen::Vector2d& b, const Eigen::Matrix2d& M) {
  const Eigen::Vector2d e = a - q, d = b - a;
  const double dMd = d.dot(M * d);
  const double eMd = e.dot(M * d);
  const double s = dMd > 0.0 ? std::clamp(-eMd / dMd, 0.0, 1.0) : 0.0;
  const Eigen::Vector2d r = e + s * d;
  return r.dot(M * r);
}

/// Sub-segment k of a region with the per-segment parts of segment_distance2 precomputed for
/// both end metrics, so a candidate costs two clamped projections (same result as
/// SearchRegion::segment_mahalanobis2).
struct SegmentTest {
  Eigen::Vector2d a, d;
  Eigen::Matrix2d M[2];
  Eigen::Vector2d Md[2];
  double dMd[2];

  SegmentTest(const SearchRegion& region, std::size_t k) {
    const std::size_t k1 = std::min(k + 1, region.centres_px.size() - 1);
    a = region.centres_px[k];
    d = region.centres_px[k1] - a;
    M[0] = region.informations_px2[k];
    M[1] = region.informations_px2[k1];
    for (int m = 0; m < 2; ++m) {
      Md[m] = M[m] * d;
      dMd[m] = d.dot(Md[m]);
    }
  }
  double distance2(const Eigen::Vector2d& q) const {
    const Eigen::Vector2d e = a - q;
    double best = kInf;
    for (int m = 0; m < 2; ++m) {
      const double s = dMd[m] > 0.0 ? std::clamp(-e.dot(Md[m]) / dMd[m], 0.0, 1.0) : 0.0;
      const Eigen::Vector2d r = e + s * d;
      best = std::min(best, r.dot(M[m] * r));
    }
    return best;
  }
};

/// Everything of the transfer that depends on the pair only (computed once per pair).
class PointTransfer {
 public:
  PointTransfer(const CameraIntrinsics& camera, const RelativePosePrior& prior,
                const PccsOptions& options)
      : camera_(camera), prior_(prior), options_(options), gate_(pccs_gate(options.confidence)) {
    if (!(camera.fx_px > 0.0) || !(camera.fy_px > 0.0)) {
      std::ostringstream msg;
      msg << "PCCS: focal lengths must be positive, got fx = " << camera.fx_px
          << " px, fy = " << camera.fy_px << " px";
      throw std::invalid_argument(msg.str());
    }
    if (!(prior.scene_depth_m > 0.0) || !(prior.scene_depth_sigma_m >= 0.0)) {
      std::ostringstream msg;
      msg << "PCCS: scene depth prior must be positive with a non-negative sigma, got "
          << prior.scene_depth_m << " +- " << prior.scene_depth_sigma_m << " m";
      throw std::invalid_argument(msg.str());
    }
    if (options.depth_samples < 1) {
      throw std::invalid_argument("PCCS: depth_samples must be >= 1, got " +
                                  std::to_string(options.depth_samples));
    }
    const Eigen::Vector3d rpy = prior.x_i_j.tail<3>();
    R_j_i_ = core::rotation_from_euler(rpy).transpose();
    dR_j_i_[0] = core::dR_droll(rpy).transpose();
    dR_j_i_[1] = core::dR_dpitch(rpy).transpose();
    dR_j_i_[2] = core::dR_dheading(rpy).transpose();
    t_i_j_ = prior.x_i_j.head<3>();
    const double k = gate_.depth_k_sigma * prior.scene_depth_sigma_m;
    depth_near_m_ = std::max(options.min_depth_m, prior.scene_depth_m - k);
    depth_far_m_ = std::max(depth_near_m_, prior.scene_depth_m + k);
  }

  /// Fills `out` (its storage is reused across calls).
  void region(const Eigen::Vector2d& u_i, SearchRegion& out) const {
    out.centres_px.clear();
    out.covariances_px2.clear();
    out.informations_px2.clear();
    out.depths_m.clear();
    out.bounds_px.setEmpty();
    out.gate_chi2 = gate_.gate_chi2;
    const int n = depth_far_m_ > depth_near_m_ ? options_.depth_samples + 1 : 1;
    const Eigen::Vector3d ray((u_i.x() - camera_.cx_px) / camera_.fx_px,
                              (u_i.y() - camera_.cy_px) / camera_.fy_px, 1.0);
    const double inv_near = 1.0 / depth_near_m_, inv_far = 1.0 / depth_far_m_;
    const double sigma2 = options_.pixel_sigma_px * options_.pixel_sigma_px;
    for (int k = 0; k < n; ++k) {
      const double inv = n == 1 ? inv_near : inv_near + (inv_far - inv_near) * k / (n - 1);
      const double d = 1.0 / inv;
      const Eigen::Vector3d w = d * ray - t_i_j_;
      const Eigen::Vector3d X = R_j_i_ * w;
      if (!(X.z() > 1e-6 * d)) continue;  // behind camera j at this depth
      const double iz = 1.0 / X.z();
      Eigen::Matrix<double, 2, 3> Jp;
      Jp << camera_.fx_px * iz, 0.0, -camera_.fx_px * X.x() * iz * iz,  //
          0.0, camera_.fy_px * iz, -camera_.fy_px * X.y() * iz * iz;
      Eigen::Matrix<double, 3, 6> dX_dx;
      dX_dx.leftCols<3>() = -R_j_i_;
      for (int a = 0; a < 3; ++a) dX_dx.col(3 + a) = dR_j_i_[a] * w;
      const Eigen::Matrix<double, 2, 6> Jx = Jp * dX_dx;
      Eigen::Matrix<double, 3, 2> dX_du = Eigen::Matrix<double, 3, 2>::Zero();
      dX_du(0, 0) = d / camera_.fx_px;
      dX_du(1, 1) = d / camera_.fy_px;
      const Eigen::Matrix2d Ju = Jp * R_j_i_ * dX_du;
      Eigen::Matrix2d S = Jx * prior_.covariance * Jx.transpose() +
                          sigma2 * (Ju * Ju.transpose() + Eigen::Matrix2d::Identity()) +
                          floor2_ * Eigen::Matrix2d::Identity();
      S = 0.5 * (S + S.transpose()).eval();
      out.centres_px.emplace_back(camera_.fx_px * X.x() * iz + camera_.cx_px,
                                  camera_.fy_px * X.y() * iz + camera_.cy_px);
      out.covariances_px2.push_back(S);
      out.informations_px2.push_back(S.inverse());
      out.depths_m.push_back(d);
    }
    for (std::size_t k = 0; k < out.centres_px.size(); ++k) {
      const Eigen::Vector2d half(std::sqrt(out.gate_chi2 * out.covariances_px2[k](0, 0)),
                                 std::sqrt(out.gate_chi2 * out.covariances_px2[k](1, 1)));
      out.bounds_px.extend(out.centres_px[k] - half);
      out.bounds_px.extend(out.centres_px[k] + half);
    }
  }

 private:
  CameraIntrinsics camera_;
  RelativePosePrior prior_;
  PccsOptions options_;
  PccsGate gate_;
  Eigen::Matrix3d R_j_i_;
  std::array<Eigen::Matrix3d, 3> dR_j_i_;
  Eigen::Vector3d t_i_j_;
  double depth_near_m_ = 0.0, depth_far_m_ = 0.0;
  double floor2_ = options_.band_floor_sigma_px * options_.band_floor_sigma_px;
};

/// Uniform bucket grid of points (compressed rows: cell_start, then point indices by cell).
class PointGrid {
 public:
  PointGrid(const std::vector<Eigen::Vector2d>& points, int width_px, int height_px, int cell_px)
      : cell_(std::max(1, cell_px)) {
    double w = width_px, h = height_px;
    for (const auto& p : points) {
      w = std::max(w, p.x() + 1.0);
      h = std::max(h, p.y() + 1.0);
    }
    cols_ = std::max(1, static_cast<int>(std::ceil(w / cell_)));
    rows_ = std::max(1, static_cast<int>(std::ceil(h / cell_)));
    std::vector<int> cell_of(points.size());
    cell_start_.assign(static_cast<std::size_t>(cols_ * rows_) + 1, 0);
    for (std::size_t k = 0; k < points.size(); ++k) {
      cell_of[k] = col(points[k].x()) + cols_ * row(points[k].y());
      ++cell_start_[cell_of[k] + 1];
    }
    for (std::size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
    index_.resize(points.size());
    std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (std::size_t k = 0; k < points.size(); ++k)
      index_[fill[cell_of[k]]++] = static_cast<int>(k);
  }

  /// Calls f(point index) for every point in the cells overlapping the box [lo, hi].
  template <class F>
  void visit(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, F&& f) const {
    const int c0 = col(lo.x()), c1 = col(hi.x()), r0 = row(lo.y()), r1 = row(hi.y());
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c) {
        const int cell = c + cols_ * r;
        for (int k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) f(index_[k]);
      }
  }

 private:
  int col(double x) const {
    return std::clamp(static_cast<int>(std::floor(x / cell_)), 0, cols_ - 1);
  }
  int row(double y) const {
    return std::clamp(static_cast<int>(std::floor(y / cell_)), 0, rows_ - 1);
  }
  double cell_;
  int cols_ = 1, rows_ = 1;
  std::vector<int> cell_start_, index_;
};

void require_descriptors(const ImageFeatures& f, const char* which) {
  if (f.size() == 0) return;
  if (f.descriptors.type() != CV_32F || f.descriptors.rows != static_cast<int>(f.size())) {
    std::ostringstream msg;
    msg << "feature matching: image " << which << " has " << f.size()
        << " points but descriptors of type " << f.descriptors.type() << " with "
        << f.descriptors.rows << " rows (expected CV_32F, one row per point)";
    throw std::invalid_argument(msg.str());
  }
}

float distance2(const cv::Mat& a, int ia, const cv::Mat& b, int ib) {
  return cv::hal::normL2Sqr_(a.ptr<float>(ia), b.ptr<float>(ib), a.cols);  // SIMD
}

/// Best and second-best candidate per feature of i, best per feature of j; then ratio test and
/// mutual check.
class MatchAccumulator {
 public:
  MatchAccumulator(std::size_t n_i, std::size_t n_j) : best_i_(n_i), best_j_(n_j) {}
  void add(int i, int j, float d2) {
    Best& b = best_i_[i];
    if (d2 < b.d2) {
      b.second_d2 = b.d2;
      b.d2 = d2;
      b.index = j;
    } else if (d2 < b.second_d2) {
      b.second_d2 = d2;
    }
    Best& c = best_j_[j];
    if (d2 < c.d2) {
      c.d2 = d2;
      c.index = i;
    }
  }
  std::vector<Match> finish(double ratio, bool mutual) const {
    std::vector<Match> out;
    const float r2 = static_cast<float>(ratio * ratio);
    for (std::size_t i = 0; i < best_i_.size(); ++i) {
      const Best& b = best_i_[i];
      if (b.index < 0) continue;
      if (!(b.d2 < r2 * b.second_d2)) continue;  // a lone candidate has second_d2 = inf
      if (mutual && best_j_[b.index].index != static_cast<int>(i)) continue;
      out.push_back({static_cast<int>(i), b.index, std::sqrt(b.d2)});
    }
    return out;
  }

 private:
  struct Best {
    float d2 = std::numeric_limits<float>::infinity();
    float second_d2 = std::numeric_limits<float>::infinity();
    int index = -1;
  };
  std::vector<Best> best_i_, best_j_;
};

}  // namespace

double SearchRegion::segment_mahalanobis2(std::size_t k, const Eigen::Vector2d& q) const {
  const std::size_t n = centres_px.size();
  if (n == 0) return kInf;
  if (n == 1) {
    const Eigen::Vector2d e = q - centres_px[0];
    return e.dot(informations_px2[0] * e);
  }
  return std::min(segment_distance2(q, centres_px[k], centres_px[k + 1], informations_px2[k]),
                  segment_distance2(q, centres_px[k], centres_px[k + 1], informations_px2[k + 1]));
}

double SearchRegion::mahalanobis2(const Eigen::Vector2d& q) const {
  double best = kInf;
  for (std::size_t k = 0; k < segments(); ++k) best = std::min(best, segment_mahalanobis2(k, q));
  return best;
}

PccsGate pccs_gate(double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) {
    std::ostringstream msg;
    msg << "PCCS: confidence must be in (0, 1), got " << confidence;
    throw std::invalid_argument(msg.str());
  }
  const double each = std::sqrt(confidence);
  // chi2 with 2 degrees of freedom: P(chi2_2 <= g) = 1 - exp(-g / 2).
  return {-2.0 * std::log1p(-each), two_sided_normal_quantile(each)};
}

SearchRegion search_region(const Eigen::Vector2d& u_i_px, const CameraIntrinsics& camera,
                           const RelativePosePrior& prior, const PccsOptions& options) {
  SearchRegion out;
  PointTransfer(camera, prior, options).region(u_i_px, out);
  return out;
}

PutativeMatches match_pose_constrained(const ImageFeatures& i, const ImageFeatures& j,
                                       const CameraIntrinsics& camera,
                                       const RelativePosePrior& prior, const PccsOptions& options) {
  require_descriptors(i, "i");
  require_descriptors(j, "j");
  PutativeMatches out;
  if (i.size() == 0 || j.size() == 0) return out;
  if (i.descriptors.cols != j.descriptors.cols) {
    throw std::invalid_argument("feature matching: descriptor widths differ (" +
                                std::to_string(i.descriptors.cols) + " and " +
                                std::to_string(j.descriptors.cols) + ")");
  }
  const PointTransfer transfer(camera, prior, options);
  const PointGrid grid(j.points_px, j.width_px, j.height_px, options.grid_cell_px);
  MatchAccumulator acc(i.size(), j.size());
  std::vector<int> accepted(j.size(), -1);
  SearchRegion region;
  for (std::size_t a = 0; a < i.size(); ++a) {
    transfer.region(i.points_px[a], region);
    const std::size_t n = region.centres_px.size();
    if (n == 0) continue;
    // Every centre lies on the epipolar line of u_i (the transfer of one ray), and every
    // ellipse within sqrt(g trace S_k) of its centre: candidates farther from the line than
    // the largest such radius cannot be in the region (a cheap test before the exact one).
    Eigen::Vector2d normal = Eigen::Vector2d::Zero();
    double max_radius2 = 0.0;
    for (const auto& S : region.covariances_px2) max_radius2 = std::max(max_radius2, S.trace());
    max_radius2 *= region.gate_chi2;
    const Eigen::Vector2d along = region.centres_px.back() - region.centres_px.front();
    if (along.norm() > 1e-9) normal = Eigen::Vector2d(-along.y(), along.x()) / along.norm();
    const double offset = normal.dot(region.centres_px.front());
    for (std::size_t k = 0; k < region.segments(); ++k) {
      const std::size_t k1 = std::min(k + 1, n - 1);
      const auto& S0 = region.covariances_px2[k];
      const auto& S1 = region.covariances_px2[k1];
      const Eigen::Vector2d half(std::sqrt(region.gate_chi2 * std::max(S0(0, 0), S1(0, 0))),
                                 std::sqrt(region.gate_chi2 * std::max(S0(1, 1), S1(1, 1))));
      const Eigen::Vector2d lo = region.centres_px[k].cwiseMin(region.centres_px[k1]) - half;
      const Eigen::Vector2d hi = region.centres_px[k].cwiseMax(region.centres_px[k1]) + half;
      const SegmentTest segment(region, k);
      // A candidate is tested against this sub-segment only; it is marked when accepted, so a
      // point inside several sub-segments is compared once and one outside this sub-segment
      // is still tested against the others (the region is their union).
      grid.visit(lo, hi, [&](int b) {
        if (accepted[b] == static_cast<int>(a)) return;
        const Eigen::Vector2d& q = j.points_px[b];
        if ((q.array() < lo.array()).any() || (q.array() > hi.array()).any()) return;
        const double across = normal.dot(q) - offset;
        if (across * across > max_radius2) return;
        if (!(segment.distance2(q) <= region.gate_chi2)) return;
        accepted[b] = static_cast<int>(a);
        ++out.descriptor_comparisons;
        acc.add(static_cast<int>(a), b,
                distance2(i.descriptors, static_cast<int>(a), j.descriptors, b));
      });
    }
  }
  out.matches = acc.finish(options.ratio, options.mutual);
  return out;
}

SceneDepthPrior scene_depth_prior(double altitude_i_m, double altitude_j_m, double t_z_i_j_m,
                                  double sigma_fraction, double sigma_floor_m) {
  const double a = altitude_i_m, b = std::max(altitude_j_m + t_z_i_j_m, 0.0);
  const double lo = std::min(a, b), hi = std::max(a, b);
  SceneDepthPrior p;
  p.depth_m = 0.5 * (lo + hi);
  p.sigma_m = (hi - lo) / 6.0 + sigma_fraction * hi + sigma_floor_m;
  return p;
}

}  // namespace nav::vision
