#include "nav/vision/essential.h"

#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "median.h"
#include "nav/core/geometry/rotation.h"
#include "nav/vision/camera_model.h"
#include "nav/vision/relative_pose_5dof.h"

namespace nav::vision {

namespace {

using detail::median;

struct Candidate {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  int in_front = 0;
  double parallax_median_rad = 0.0;
  double sampson_median = 0.0;  ///< median |Sampson distance| over the inliers, normalised
  /// Angle between camera i's optical axis and the normal of the plane fitted to the inliers
  /// triangulated in front (pi/2 when fewer than 3).
  double floor_tilt_rad = M_PI / 2.0;
};

int cv_method(RobustMethod method) {
  switch (method) {
    case RobustMethod::kRansac:
      return cv::RANSAC;
    case RobustMethod::kUsacMagsac:
      return cv::USAC_MAGSAC;
    case RobustMethod::kLmeds:
      break;
  }
  return cv::LMEDS;
}

Eigen::Vector3d bearing(const Eigen::Vector2d& x) { return {x.x(), x.y(), 1.0}; }

/// Angle between the z axis and the normal of the least-squares plane through the points.
double plane_tilt_rad(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 3) return M_PI / 2.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : points) scatter += (p - mean) * (p - mean).transpose();
  // The normal is the direction of least spread: the first eigenvector (ascending order).
  const Eigen::Vector3d normal =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(0);
  return std::acos(std::min(1.0, std::abs(normal.z())));
}

/// Cheirality count, median parallax, median Sampson distance and floor tilt of a candidate
/// over the inliers.
void score(Candidate& c, const std::vector<Eigen::Vector2d>& xi,
           const std::vector<Eigen::Vector2d>& xj, const std::vector<int>& inliers) {
  c.in_front = 0;
  std::vector<double> parallax, sampson;
  std::vector<Eigen::Vector3d> points_i;
  parallax.reserve(inliers.size());
  const Eigen::Matrix3d E = core::skew(c.t) * c.R;
  for (int k : inliers) {
    const auto sk = static_cast<std::size_t>(k);
    double di = 0.0, dj = 0.0;
    if (triangulate_depths(c.R, c.t, xi[sk], xj[sk], &di, &dj) && di > 0.0 && dj > 0.0) {
      ++c.in_front;
      points_i.push_back(di * bearing(xi[sk]));
    }
    const Eigen::Vector3d a = bearing(xi[sk]).normalized();
    const Eigen::Vector3d b = (c.R * bearing(xj[sk])).normalized();
    parallax.push_back(std::atan2(a.cross(b).norm(), a.dot(b)));
    sampson.push_back(std::abs(sampson_distance(E, xi[sk], xj[sk])));
  }
  c.parallax_median_rad = median(std::move(parallax));
  c.sampson_median = median(std::move(sampson));
  c.floor_tilt_rad = plane_tilt_rad(points_i);
}

constexpr double kTwinRotationRad = 2.0 * M_PI / 180.0;
constexpr double kTwinBaselineRad = 30.0 * M_PI / 180.0;
constexpr double kSameFloorRad = 5.0 * M_PI / 180.0;

double angle_between(const Candidate& a, const Candidate& b) {
  return Eigen::AngleAxisd(a.R.transpose() * b.R).angle();
}

/// With a prior (essential.h): among the candidates that put as many points in front as the
/// best, the one nearest the prior's predicted measurement in Mahalanobis distance. A candidate
/// whose baseline is along the optical axis has no azimuth: last resort only.
const Candidate* choose_with_prior(const std::vector<Candidate>& candidates, int best_count,
                                   const PredictedZ& predicted, double ambiguity_ratio) {
  const auto S = predicted.covariance.ldlt();
  const Candidate* chosen = nullptr;
  double chosen_key = 0.0;
  for (const Candidate& c : candidates) {
    if (c.in_front < ambiguity_ratio * best_count) continue;
    double key = std::numeric_limits<double>::max();
    try {
      const Vec5 r = z_minus(z_from_rotation_translation(c.R, c.t), predicted.z);
      key = r.dot(S.solve(r));
    } catch (const std::domain_error&) {
    }
    if (chosen == nullptr || key < chosen_key) {
      chosen = &c;
      chosen_key = key;
    }
  }
  return chosen;
}

/// Without a prior (essential.h): among the candidates that put as many points in front as the
/// best and fit the matches as well, the one whose points lie on the least tilted floor; an
/// error message when another pose fits as well and the floor cannot tell them apart.
const Candidate* choose_without_prior(const std::vector<Candidate>& candidates, int best_count,
                                      double focal, const EssentialOptions& o, std::string* why) {
  std::vector<const Candidate*> tied;
  double best_sampson = std::numeric_limits<double>::max();
  for (const Candidate& c : candidates) {
    if (c.in_front < o.ambiguity_ratio * best_count) continue;
    tied.push_back(&c);
    best_sampson = std::min(best_sampson, c.sampson_median);
  }
  const double fit_limit = 2.0 * best_sampson + o.min_sigma_px / focal;
  std::vector<const Candidate*> fits;
  for (const Candidate* c : tied) {
    if (c->sampson_median <= fit_limit) fits.push_back(c);
  }
  const auto flattest = *std::min_element(fits.begin(), fits.end(), [](auto* a, auto* b) {
    return a->floor_tilt_rad < b->floor_tilt_rad;
  });
  // Without parallax no pose is defined and the parallax test that follows says so.
  if (flattest->parallax_median_rad * focal < o.min_parallax_px) return flattest;
  const double max_tilt = o.floor_max_tilt_deg * M_PI / 180.0;
  const double min_gap = o.floor_min_tilt_gap_deg * M_PI / 180.0;
  for (const Candidate* c : fits) {
    // Seeds of one reconstruction differ by noise (most in the baseline of a short one) and
    // see the same floor; a planar twin turns the camera by about the baseline-to-depth angle
    // and tilts the floor by the baseline's angle to the floor's normal.
    const double rotation_apart = angle_between(*c, *flattest);
    const double baseline_apart = std::acos(std::clamp(c->t.dot(flattest->t), -1.0, 1.0));
    const bool twin = (rotation_apart > kTwinRotationRad || baseline_apart > kTwinBaselineRad) &&
                      c->floor_tilt_rad > flattest->floor_tilt_rad + kSameFloorRad;
    if (!twin || (flattest->floor_tilt_rad <= max_tilt &&
                  c->floor_tilt_rad >= flattest->floor_tilt_rad + min_gap)) {
      continue;
    }
    *why = "essential: planar ambiguity without a prior: two poses " +
           std::to_string(rotation_apart * 180.0 / M_PI) + " deg (baselines " +
           std::to_string(baseline_apart * 180.0 / M_PI) +
           " deg) apart fit the matches equally, their floors tilted " +
           std::to_string(flattest->floor_tilt_rad * 180.0 / M_PI) + " and " +
           std::to_string(c->floor_tilt_rad * 180.0 / M_PI) + " deg (a floor is tilted at most " +
           std::to_string(o.floor_max_tilt_deg) + " deg and " +
           std::to_string(o.floor_min_tilt_gap_deg) + " deg less than any other)";
    return nullptr;
  }
  return flattest;
}

/// Orthonormal basis of the plane orthogonal to the unit vector t.
Eigen::Matrix<double, 3, 2> tangent_basis(const Eigen::Vector3d& t) {
  const Eigen::Vector3d a = std::abs(t.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  Eigen::Matrix<double, 3, 2> B;
  B.col(0) = t.cross(a).normalized();
  B.col(1) = t.cross(B.col(0)).normalized();
  return B;
}

Eigen::Matrix3d exp_so3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-15) return Eigen::Matrix3d::Identity() + core::skew(w);
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

double sampson_cost(const std::vector<Eigen::Vector2d>& xi, const std::vector<Eigen::Vector2d>& xj,
                    const Eigen::Matrix3d& R, const Eigen::Vector3d& t, Eigen::VectorXd* r) {
  const Eigen::Matrix3d E = core::skew(t) * R;
  r->resize(static_cast<Eigen::Index>(xi.size()));
  for (std::size_t k = 0; k < xi.size(); ++k) {
    (*r)[static_cast<Eigen::Index>(k)] = sampson_distance(E, xi[k], xj[k]);
  }
  return r->squaredNorm();
}

}  // namespace

double sampson_distance(const Eigen::Matrix3d& E, const Eigen::Vector2d& x_i,
                        const Eigen::Vector2d& x_j) {
  const Eigen::Vector3d bi = bearing(x_i), bj = bearing(x_j);
  const Eigen::Vector3d Ebj = E * bj;
  const Eigen::Vector3d Etbi = E.transpose() * bi;
  const double denom = Ebj.head<2>().squaredNorm() + Etbi.head<2>().squaredNorm();
  // Signed, so that Gauss-Newton sees a smooth residual.
  return denom > 0.0 ? bi.dot(Ebj) / std::sqrt(denom) : 0.0;
}

int polish_sampson(const std::vector<Eigen::Vector2d>& x_i, const std::vector<Eigen::Vector2d>& x_j,
                   int iterations, Eigen::Matrix3d* R_i_j, Eigen::Vector3d* t_i_j_unit) {
  if (x_i.size() < 6 || x_i.size() != x_j.size()) return 0;
  Eigen::Matrix3d R = *R_i_j;
  Eigen::Vector3d t = t_i_j_unit->normalized();
  Eigen::VectorXd r, r_step;
  double cost = sampson_cost(x_i, x_j, R, t, &r);
  double lambda = 1e-4;
  int accepted = 0;
  const auto n = static_cast<Eigen::Index>(x_i.size());
  for (int it = 0; it < iterations; ++it) {
    // Central-difference Jacobian of the residuals in the 5 local coordinates.
    const Eigen::Matrix<double, 3, 2> B = tangent_basis(t);
    auto apply = [&](const Eigen::Matrix<double, 5, 1>& d, Eigen::Matrix3d* Rd, Eigen::Vector3d* td) {
      *Rd = R * exp_so3(d.head<3>());
      *td = (t + B * d.tail<2>()).normalized();
    };
    Eigen::MatrixXd J(n, 5);
    const double h = 1e-7;
    for (int c = 0; c < 5; ++c) {
      Eigen::Matrix<double, 5, 1> d = Eigen::Matrix<double, 5, 1>::Zero();
      Eigen::Matrix3d Rp, Rm;
      Eigen::Vector3d tp, tm;
      Eigen::VectorXd rp, rm;
      d[c] = h;
      apply(d, &Rp, &tp);
      d[c] = -h;
      apply(d, &Rm, &tm);
      sampson_cost(x_i, x_j, Rp, tp, &rp);
      sampson_cost(x_i, x_j, Rm, tm, &rm);
      J.col(c) = (rp - rm) / (2.0 * h);
    }
    const Eigen::Matrix<double, 5, 5> H = J.transpose() * J;
    const Eigen::Matrix<double, 5, 1> g = J.transpose() * r;
    bool improved = false;
    for (int tries = 0; tries < 5 && !improved; ++tries) {
      Eigen::Matrix<double, 5, 5> A = H;
      A.diagonal() *= (1.0 + lambda);
      const Eigen::Matrix<double, 5, 1> step = -A.ldlt().solve(g);
      if (!step.allFinite()) break;
      Eigen::Matrix3d Rn;
      Eigen::Vector3d tn;
      apply(step, &Rn, &tn);
      const double new_cost = sampson_cost(x_i, x_j, Rn, tn, &r_step);
      if (new_cost < cost) {
        const double decrease = (cost - new_cost) / std::max(cost, 1e-300);
        R = Rn;
        t = tn;
        r = r_step;
        cost = new_cost;
        lambda = std::max(1e-8, lambda * 0.1);
        improved = true;
        ++accepted;
        if (decrease < 1e-10) it = iterations;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  *R_i_j = R;
  *t_i_j_unit = t;
  return accepted;
}

bool triangulate_depths(const Eigen::Matrix3d& R_i_j, const Eigen::Vector3d& t_i_j,
                        const Eigen::Vector2d& x_i, const Eigen::Vector2d& x_j, double* depth_i,
                        double* depth_j) {
  // d_i b_i = d_j R b_j + t  ->  [b_i, -R b_j] [d_i; d_j] = t in least squares; with b = [x; 1]
  // the unknowns are depths along the optical axes.
  Eigen::Matrix<double, 3, 2> A;
  A.col(0) = bearing(x_i);
  A.col(1) = -(R_i_j * bearing(x_j));
  const Eigen::Matrix2d AtA = A.transpose() * A;
  const double det = AtA.determinant();
  if (std::abs(det) < 1e-12 * AtA.trace() * AtA.trace()) return false;
  const Eigen::Vector2d d = AtA.inverse() * (A.transpose() * t_i_j);
  *depth_i = d[0];
  *depth_j = d[1];
  return true;
}

EssentialEstimate estimate_essential(const ImageFeatures& features_i,
                                     const ImageFeatures& features_j,
                                     const PutativeMatches& matches,
                                     const CameraIntrinsics& camera,
                                     const EssentialOptions& options,
                                     const RelativePosePrior* prior) {
  EssentialEstimate out;
  const int n = static_cast<int>(matches.matches.size());
  if (n < std::max(options.min_matches, 5)) {
    out.reason = "essential: " + std::to_string(n) + " putative matches, at least " +
                 std::to_string(std::max(options.min_matches, 5)) + " needed";
    return out;
  }
  std::vector<Eigen::Vector2d> xi, xj;
  std::vector<cv::Point2d> pi, pj;
  for (const Match& m : matches.matches) {
    xi.push_back(normalised_from_pixel(camera, features_i.points_px[static_cast<std::size_t>(m.index_i)]));
    xj.push_back(normalised_from_pixel(camera, features_j.points_px[static_cast<std::size_t>(m.index_j)]));
    pi.emplace_back(xi.back().x(), xi.back().y());
    pj.emplace_back(xj.back().x(), xj.back().y());
  }
  // OpenCV's convention is points2^T E points1 = 0 with X2 = R X1 + t: points1 = j, points2 = i
  // gives E, R, t of this library's convention directly.
  const double focal = 0.5 * (camera.fx_px + camera.fy_px);
  cv::Mat mask;
  cv::Mat E_cv = cv::findEssentialMat(pj, pi, cv::Mat::eye(3, 3, CV_64F), cv_method(options.method),
                                      options.confidence, options.threshold_px / focal,
                                      options.max_iterations, mask);
  if (E_cv.rows != 3 || E_cv.cols != 3) {
    out.reason = "essential: the robust estimator found no model among " + std::to_string(n) +
                 " matches" + (E_cv.empty() ? "" : " (ambiguous: several 5-point solutions)");
    return out;
  }
  for (int k = 0; k < n; ++k) {
    if (mask.at<uchar>(k)) out.inliers.push_back(k);
  }
  if (out.inliers.size() < 5) {
    out.reason = "essential: only " + std::to_string(out.inliers.size()) + " inliers";
    return out;
  }

  std::vector<Candidate> candidates;
  cv::Mat R1, R2, t_cv;
  cv::decomposeEssentialMat(E_cv, R1, R2, t_cv);
  for (const cv::Mat& R : {R1, R2}) {
    for (double sign : {1.0, -1.0}) {
      Candidate c;
      cv::cv2eigen(R, c.R);
      Eigen::Vector3d t;
      cv::cv2eigen(t_cv, t);
      c.t = sign * t.normalized();
      candidates.push_back(c);
    }
  }
  if (options.planar_candidates && out.inliers.size() >= 4) {
    std::vector<cv::Point2d> hi, hj;
    for (int k : out.inliers) {
      hi.push_back(pi[static_cast<std::size_t>(k)]);
      hj.push_back(pj[static_cast<std::size_t>(k)]);
    }
    // H maps j to i: x_i ~ H x_j with H = R + t n^T / d (plane in camera j).
    cv::Mat H = cv::findHomography(hj, hi, cv::LMEDS);
    if (!H.empty()) {
      std::vector<cv::Mat> Rs, ts, normals;
      cv::decomposeHomographyMat(H, cv::Mat::eye(3, 3, CV_64F), Rs, ts, normals);
      for (std::size_t s = 0; s < Rs.size(); ++s) {
        Candidate c;
        cv::cv2eigen(Rs[s], c.R);
        Eigen::Vector3d t;
        cv::cv2eigen(ts[s], t);
        if (t.norm() < 1e-12) continue;
        c.t = t.normalized();
        candidates.push_back(c);
      }
    }
  }
  for (Candidate& c : candidates) score(c, xi, xj, out.inliers);
  int best_count = 0;
  for (const Candidate& c : candidates) best_count = std::max(best_count, c.in_front);
  if (best_count == 0) {
    out.reason = "essential: no decomposition puts the inliers in front of both cameras";
    return out;
  }
  // The prior's predicted measurement and covariance (relative_pose_5dof.h); none when the
  // prior's baseline has no defined azimuth.
  PredictedZ predicted;
  bool use_prior = false;
  if (prior != nullptr) {
    try {
      predicted = predict_z(*prior);
      use_prior = true;
    } catch (const std::domain_error&) {
      use_prior = false;
    }
  }
  const Candidate* chosen =
      use_prior ? choose_with_prior(candidates, best_count, predicted, options.ambiguity_ratio)
                : choose_without_prior(candidates, best_count, focal, options, &out.reason);
  if (chosen == nullptr) return out;
  if (chosen->parallax_median_rad * focal < options.min_parallax_px) {
    out.reason = "essential: median parallax " + std::to_string(chosen->parallax_median_rad * focal) +
                 " px below " + std::to_string(options.min_parallax_px) +
                 " px (pure rotation or negligible baseline: translation unobservable)";
    return out;
  }
  Candidate polished = *chosen;
  for (int round = 0; round < options.polish_rounds && options.polish_iterations > 0; ++round) {
    std::vector<Eigen::Vector2d> pi_in, pj_in;
    for (int k : out.inliers) {
      pi_in.push_back(xi[static_cast<std::size_t>(k)]);
      pj_in.push_back(xj[static_cast<std::size_t>(k)]);
    }
    polish_sampson(pi_in, pj_in, options.polish_iterations, &polished.R, &polished.t);
    // Re-select the inliers among all matches at k robust sigmas of the polished model
    // (sigma = 1.4826 median |d| over the current inliers, floored at the pixel noise floor).
    const Eigen::Matrix3d E = core::skew(polished.t) * polished.R;
    std::vector<double> d_in;
    for (int k : out.inliers) {
      d_in.push_back(std::abs(sampson_distance(E, xi[static_cast<std::size_t>(k)], xj[static_cast<std::size_t>(k)])));
    }
    auto mid = d_in.begin() + static_cast<std::ptrdiff_t>(d_in.size() / 2);
    std::nth_element(d_in.begin(), mid, d_in.end());
    const double sigma = std::max(1.4826 * *mid, options.min_sigma_px / focal);
    std::vector<int> reselected;
    for (int k = 0; k < n; ++k) {
      const auto sk = static_cast<std::size_t>(k);
      if (std::abs(sampson_distance(E, xi[sk], xj[sk])) <= options.inlier_k_sigma * sigma) {
        reselected.push_back(k);
      }
    }
    if (reselected.size() < 5) break;
    out.inliers = std::move(reselected);
  }
  chosen = &polished;
  // Keep only the inliers in front of both cameras under the chosen pose.
  std::vector<int> in_front;
  for (int k : out.inliers) {
    const auto sk = static_cast<std::size_t>(k);
    double di = 0.0, dj = 0.0;
    if (triangulate_depths(chosen->R, chosen->t, xi[sk], xj[sk], &di, &dj) && di > 0.0 && dj > 0.0) {
      in_front.push_back(k);
    }
  }
  out.inliers = std::move(in_front);
  out.R_i_j = chosen->R;
  out.t_i_j_unit = chosen->t;
  out.E = core::skew(chosen->t) * chosen->R;
  out.ok = true;
  return out;
}

}  // namespace nav::vision
