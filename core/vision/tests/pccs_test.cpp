// Tests of pccs.h on synthetic scenes with known truth (synthetic_two_view.h):
//  - containment: with the prior's covariance exact (truth drawn from the prior), the true
//    correspondences fall inside their regions at the configured confidence (counted); with
//    the covariance scaled down 10x many fall outside (Eustice et al. RSS 2005, Fig. 4);
//  - matching: PCCS compares far fewer descriptors than the exhaustive search, finds the true
//    matches, and keeps finding them on repetitive texture where the exhaustive ratio test
//    fails;
//  - the grid-indexed search equals a brute-force search over every pair;
//  - bad inputs throw with a message.

#include "nav/vision/pccs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <random>
#include <stdexcept>

#include "nav/vision/matching.h"
#include "synthetic_two_view.h"

namespace nav::vision {
namespace {

using test::deg;

constexpr double kDepthM = 3.5;
constexpr double kDepthSigmaM = 0.3;
constexpr double kPixelSigmaPx = 0.5;

RelativePosePrior prior_around(const Vec6& mean, const Mat6& covariance) {
  RelativePosePrior p;
  p.x_i_j = mean;
  p.covariance = covariance;
  p.scene_depth_m = kDepthM;
  p.scene_depth_sigma_m = kDepthSigmaM;
  return p;
}

struct Containment {
  long inside = 0, total = 0;
  double fraction() const { return static_cast<double>(inside) / static_cast<double>(total); }
};

/// Over `trials` priors whose error is drawn from P (truth = prior mean + error), the fraction
/// of true correspondences inside their regions computed with covariance `scale` * P.
Containment containment(double scale, int trials, int points, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const Mat6 P = test::default_prior_covariance();
  Containment c;
  PccsOptions options;
  options.pixel_sigma_px = kPixelSigmaPx;
  for (int trial = 0; trial < trials; ++trial) {
    const Vec6 truth = test::default_x_i_j();
    const RelativePosePrior prior = prior_around(truth - test::draw(rng, P), scale * P);
    const test::TwoViewScene scene =
        test::make_scene(rng, truth, points, kDepthM, kDepthSigmaM, kPixelSigmaPx);
    for (std::size_t k = 0; k < scene.size(); ++k) {
      const SearchRegion region = search_region(scene.u_i[k], scene.camera, prior, options);
      c.inside += region.contains(scene.u_j[k]) ? 1 : 0;
      ++c.total;
    }
  }
  return c;
}

TEST(Pccs, TrueCorrespondencesInsideTheirRegionsAtTheConfidence) {
  const Containment c = containment(1.0, 200, 100, 1);
  std::cout << "PCCS containment at confidence 0.999, exact prior covariance: " << c.inside << " / "
            << c.total << " = " << c.fraction() << "\n";
  RecordProperty("containment_exact", std::to_string(c.fraction()));
  EXPECT_GE(c.fraction(), 0.999) << c.inside << " of " << c.total;
}

TEST(Pccs, OverconfidentPriorLosesCorrespondences) {
  const Containment c = containment(0.1, 200, 100, 1);
  std::cout << "PCCS containment with the covariance scaled down 10x: " << c.inside << " / "
            << c.total << " = " << c.fraction() << "\n";
  RecordProperty("containment_overconfident", std::to_string(c.fraction()));
  EXPECT_LT(c.fraction(), 0.99) << c.inside << " of " << c.total;
}

TEST(Pccs, GateFromConfidence) {
  // chi2_2^-1(sqrt(0.999)) = -2 ln(1 - sqrt(0.999)) and the two-sided normal quantile of
  // sqrt(0.999) = 0.9995 is 3.4808 (tables).
  const PccsGate g = pccs_gate(0.999);
  EXPECT_NEAR(g.gate_chi2, -2.0 * std::log(1.0 - std::sqrt(0.999)), 1e-12);
  EXPECT_NEAR(g.depth_k_sigma, 3.4808, 1e-3);
  EXPECT_NEAR(std::erfc(g.depth_k_sigma / std::sqrt(2.0)), 1.0 - std::sqrt(0.999), 1e-12);
  EXPECT_THROW(pccs_gate(1.0), std::invalid_argument);
  EXPECT_THROW(pccs_gate(0.0), std::invalid_argument);
}

TEST(Pccs, RegionIsTheEpipolarSegmentOverTheDepthInterval) {
  // Without pose uncertainty and pixel noise the region collapses onto the epipolar line:
  // every centre satisfies x_j^T E x_i = 0 with E = R^T [t]x, and the ends are the transfers
  // at the ends of the depth interval.
  RelativePosePrior prior = prior_around(test::default_x_i_j(), Mat6::Zero());
  PccsOptions options;
  options.pixel_sigma_px = 1e-3;
  const CameraIntrinsics cam = test::sim_camera();
  const Eigen::Vector2d u_i(300.0, 700.0);
  const SearchRegion r = search_region(u_i, cam, prior, options);
  ASSERT_EQ(r.centres_px.size(), static_cast<std::size_t>(options.depth_samples + 1));
  const Eigen::Matrix3d R = core::pose_rotation(prior.x_i_j);
  const Eigen::Vector3d t = core::pose_translation(prior.x_i_j);
  Eigen::Matrix3d tx;
  tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  const Eigen::Matrix3d E = R.transpose() * tx;  // x_j^T E x_i = 0
  const Eigen::Vector3d x_i((u_i.x() - 640.0) / 1000.0, (u_i.y() - 512.0) / 1000.0, 1.0);
  for (const auto& c : r.centres_px) {
    const Eigen::Vector3d x_j((c.x() - 640.0) / 1000.0, (c.y() - 512.0) / 1000.0, 1.0);
    EXPECT_NEAR(x_j.dot(E * x_i), 0.0, 1e-12);
  }
  const double k = pccs_gate(options.confidence).depth_k_sigma;
  EXPECT_NEAR(r.depths_m.front(), kDepthM - k * kDepthSigmaM, 1e-12);
  EXPECT_NEAR(r.depths_m.back(), kDepthM + k * kDepthSigmaM, 1e-12);
  const Eigen::Vector3d X_far = R.transpose() * (r.depths_m.back() * x_i - t);
  EXPECT_LT((r.centres_px.back() - test::project(cam, X_far)).norm(), 1e-9);
  // A point 3 px off the line is outside, a point on the line between two samples inside.
  const Eigen::Vector2d mid = 0.5 * (r.centres_px[3] + r.centres_px[4]);
  EXPECT_TRUE(r.contains(mid));
  const Eigen::Vector2d along = (r.centres_px[4] - r.centres_px[3]).normalized();
  EXPECT_FALSE(r.contains(mid + 3.0 * Eigen::Vector2d(-along.y(), along.x())));
}

TEST(Pccs, BandFloorAddsItsVarianceToEveryEllipse) {
  // The floor adds sigma^2 I to every S and moves no centre: a point 3 px off the line, outside
  // the exact band, is inside once the floor is 2 px (gate sqrt(g) ~ 3.9 sigma), and the
  // band's half-width across the line grows to sqrt(g (S_nn + floor^2)).
  const RelativePosePrior prior = prior_around(test::default_x_i_j(), Mat6::Zero());
  PccsOptions options;
  options.pixel_sigma_px = 1e-3;
  const CameraIntrinsics cam = test::sim_camera();
  const Eigen::Vector2d u_i(300.0, 700.0);
  const SearchRegion exact = search_region(u_i, cam, prior, options);
  options.band_floor_sigma_px = 2.0;
  const SearchRegion floored = search_region(u_i, cam, prior, options);
  ASSERT_EQ(exact.centres_px.size(), floored.centres_px.size());
  for (std::size_t k = 0; k < exact.centres_px.size(); ++k) {
    EXPECT_EQ(exact.centres_px[k], floored.centres_px[k]);
    EXPECT_TRUE(floored.covariances_px2[k].isApprox(
        exact.covariances_px2[k] + 4.0 * Eigen::Matrix2d::Identity(), 1e-12));
  }
  const Eigen::Vector2d mid = 0.5 * (exact.centres_px[3] + exact.centres_px[4]);
  const Eigen::Vector2d along = (exact.centres_px[4] - exact.centres_px[3]).normalized();
  const Eigen::Vector2d normal(-along.y(), along.x());
  EXPECT_FALSE(exact.contains(mid + 3.0 * normal));
  EXPECT_TRUE(floored.contains(mid + 3.0 * normal));
  const double half_width = std::sqrt(floored.gate_chi2 * 4.0);  // S ~ floor^2 I here
  EXPECT_TRUE(floored.contains(mid + 0.99 * half_width * normal));
  EXPECT_FALSE(floored.contains(mid + 1.01 * half_width * normal));
}

/// Features of a scene with descriptors: each point's descriptor is prototype + unique part,
/// each observation adds its own noise; `distractors` unmatched features per image.
struct FeaturePair {
  ImageFeatures i, j;
  std::vector<int> truth_j;  ///< Index in j of the true match of feature a of i (-1: none).
};

FeaturePair make_features(std::mt19937& rng, const test::TwoViewScene& s, int prototypes,
                          double unique_sigma, double noise_sigma, int distractors) {
  std::normal_distribution<float> n01;
  const int dim = 128;
  cv::Mat proto(prototypes, dim, CV_32F);
  for (int r = 0; r < prototypes; ++r)
    for (int c = 0; c < dim; ++c) proto.at<float>(r, c) = n01(rng);
  std::uniform_int_distribution<int> pick(0, prototypes - 1);
  const int n = static_cast<int>(s.size());
  FeaturePair f;
  f.i.descriptors.create(n + distractors, dim, CV_32F);
  f.j.descriptors.create(n + distractors, dim, CV_32F);
  std::vector<int> perm(n + distractors);
  for (int k = 0; k < n + distractors; ++k) perm[k] = k;
  std::shuffle(perm.begin(), perm.end(), rng);  // j's order differs from i's
  f.truth_j.assign(n + distractors, -1);
  f.i.points_px.resize(n + distractors);
  f.j.points_px.resize(n + distractors);
  std::uniform_real_distribution<double> ux(0.0, 1280.0), uy(0.0, 1024.0);
  for (int k = 0; k < n + distractors; ++k) {
    const bool real = k < n;
    const int p = pick(rng);
    std::vector<float> base(dim);
    for (int c = 0; c < dim; ++c)
      base[c] = proto.at<float>(p, c) + static_cast<float>(unique_sigma) * n01(rng);
    const auto noisy = [&](cv::Mat& m, int row) {
      for (int c = 0; c < dim; ++c)
        m.at<float>(row, c) = base[c] + static_cast<float>(noise_sigma) * n01(rng);
    };
    noisy(f.i.descriptors, k);
    f.i.points_px[k] = real ? s.u_i[k] : Eigen::Vector2d(ux(rng), uy(rng));
    if (!real) {  // a distractor in j gets its own descriptor
      for (int c = 0; c < dim; ++c)
        base[c] = proto.at<float>(pick(rng), c) + static_cast<float>(unique_sigma) * n01(rng);
    }
    noisy(f.j.descriptors, perm[k]);
    f.j.points_px[perm[k]] = real ? s.u_j[k] : Eigen::Vector2d(ux(rng), uy(rng));
    if (real) f.truth_j[k] = perm[k];
  }
  f.i.width_px = f.j.width_px = 1280;
  f.i.height_px = f.j.height_px = 1024;
  return f;
}

struct Score {
  int correct = 0, wrong = 0;
};

Score score(const PutativeMatches& m, const FeaturePair& f) {
  Score s;
  for (const Match& x : m.matches) (f.truth_j[x.index_i] == x.index_j ? s.correct : s.wrong)++;
  return s;
}

TEST(Pccs, FewerComparisonsThanExhaustiveAndFindsTheTrueMatches) {
  std::mt19937 rng(2);
  const Mat6 P = test::default_prior_covariance();
  const Vec6 truth = test::default_x_i_j();
  const RelativePosePrior prior = prior_around(truth - test::draw(rng, P), P);
  const test::TwoViewScene scene =
      test::make_scene(rng, truth, 1500, kDepthM, kDepthSigmaM, kPixelSigmaPx);
  const FeaturePair f = make_features(rng, scene, 1500, 1.0, 0.15, 500);
  const PutativeMatches pccs = match_pose_constrained(f.i, f.j, scene.camera, prior, PccsOptions{});
  const PutativeMatches full = match_unconstrained(f.i, f.j, MatchingOptions{});
  const Score sp = score(pccs, f), sf = score(full, f);
  std::cout << "distinct texture: PCCS " << pccs.descriptor_comparisons << " comparisons, "
            << sp.correct << " correct / " << sp.wrong << " wrong; exhaustive "
            << full.descriptor_comparisons << " comparisons, " << sf.correct << " correct / "
            << sf.wrong << " wrong (" << scene.size() << " true correspondences)\n";
  EXPECT_EQ(full.descriptor_comparisons, f.i.size() * f.j.size());
  EXPECT_LT(pccs.descriptor_comparisons, full.descriptor_comparisons / 10);
  EXPECT_GE(sp.correct, static_cast<int>(0.95 * static_cast<double>(scene.size())));
  EXPECT_LE(sp.wrong, 3);
}

TEST(Pccs, RepetitiveTextureMatchedInsideRegionsOnly) {
  // 60 prototypes shared by 2000 features with a small unique part: across the whole image
  // the nearest and second-nearest neighbours are often equally close (the ratio test rejects
  // them); inside a region there are few look-alikes.
  std::mt19937 rng(4);
  const Mat6 P = test::default_prior_covariance();
  const Vec6 truth = test::default_x_i_j();
  const RelativePosePrior prior = prior_around(truth - test::draw(rng, P), P);
  const test::TwoViewScene scene =
      test::make_scene(rng, truth, 1500, kDepthM, kDepthSigmaM, kPixelSigmaPx);
  const FeaturePair f = make_features(rng, scene, 60, 0.05, 0.06, 500);
  const PutativeMatches pccs = match_pose_constrained(f.i, f.j, scene.camera, prior, PccsOptions{});
  const PutativeMatches full = match_unconstrained(f.i, f.j, MatchingOptions{});
  const Score sp = score(pccs, f), sf = score(full, f);
  std::cout << "repetitive texture: PCCS " << sp.correct << " correct / " << sp.wrong
            << " wrong; exhaustive " << sf.correct << " correct / " << sf.wrong << " wrong ("
            << scene.size() << " true correspondences)\n";
  EXPECT_GT(sp.correct, 2 * sf.correct);
  EXPECT_GE(sp.correct, static_cast<int>(0.5 * static_cast<double>(scene.size())));
  EXPECT_LT(sp.wrong, sp.correct / 10);
}

TEST(Pccs, GridSearchEqualsBruteForce) {
  // Reference: every pair gated with SearchRegion::contains, the ratio test and the mutual
  // check written out directly.
  std::mt19937 rng(8);
  const Mat6 P = test::default_prior_covariance();
  const Vec6 truth = test::default_x_i_j();
  const RelativePosePrior prior = prior_around(truth - test::draw(rng, P), P);
  const test::TwoViewScene scene =
      test::make_scene(rng, truth, 400, kDepthM, kDepthSigmaM, kPixelSigmaPx);
  const FeaturePair f = make_features(rng, scene, 30, 0.1, 0.06, 200);
  PccsOptions options;
  options.grid_cell_px = 17;  // an odd size, cells not aligned with anything
  const PutativeMatches got = match_pose_constrained(f.i, f.j, scene.camera, prior, options);

  const int ni = static_cast<int>(f.i.size()), nj = static_cast<int>(f.j.size());
  std::vector<std::vector<double>> d(ni, std::vector<double>(nj, -1.0));
  std::size_t comparisons = 0;
  for (int a = 0; a < ni; ++a) {
    const SearchRegion r = search_region(f.i.points_px[a], scene.camera, prior, options);
    for (int b = 0; b < nj; ++b)
      if (r.contains(f.j.points_px[b])) {
        d[a][b] = cv::norm(f.i.descriptors.row(a), f.j.descriptors.row(b), cv::NORM_L2);
        ++comparisons;
      }
  }
  std::map<int, int> expected;
  for (int a = 0; a < ni; ++a) {
    int best = -1;
    double d1 = 1e300, d2 = 1e300;
    for (int b = 0; b < nj; ++b) {
      if (d[a][b] < 0.0) continue;
      if (d[a][b] < d1) {
        d2 = d1;
        d1 = d[a][b];
        best = b;
      } else if (d[a][b] < d2)
        d2 = d[a][b];
    }
    if (best < 0 || !(d1 < 0.8 * d2)) continue;
    bool mutual = true;
    for (int c = 0; c < ni; ++c) mutual = mutual && !(d[c][best] >= 0.0 && d[c][best] < d1);
    if (mutual) expected[a] = best;
  }
  EXPECT_EQ(got.descriptor_comparisons, comparisons);
  std::map<int, int> actual;
  for (const Match& m : got.matches) actual[m.index_i] = m.index_j;
  EXPECT_EQ(actual, expected);
  EXPECT_GT(actual.size(), 100u);
}

TEST(Pccs, BadInputsThrowWithAMessage) {
  ImageFeatures a, b;
  a.points_px.assign(3, Eigen::Vector2d(10.0, 10.0));
  a.descriptors = cv::Mat::zeros(3, 128, CV_8U);  // wrong type
  b = a;
  b.descriptors = cv::Mat::zeros(3, 128, CV_32F);
  const RelativePosePrior prior = prior_around(test::default_x_i_j(), Mat6::Identity() * 1e-4);
  try {
    match_pose_constrained(a, b, test::sim_camera(), prior, PccsOptions{});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("image i"), std::string::npos) << e.what();
  }
  RelativePosePrior no_depth = prior;
  no_depth.scene_depth_m = 0.0;
  EXPECT_THROW(search_region({1.0, 1.0}, test::sim_camera(), no_depth, PccsOptions{}),
               std::invalid_argument);
  // No features: no matches, no comparisons.
  const PutativeMatches none =
      match_pose_constrained(ImageFeatures{}, b, test::sim_camera(), prior, PccsOptions{});
  EXPECT_TRUE(none.matches.empty());
  EXPECT_EQ(none.descriptor_comparisons, 0u);
}

// Over relief the shared scene lies between the floor below camera i and the floor below
// camera j (seen from camera i): the prior's 3-sigma interval spans both, each with its own
// margin; equal depths give the one-camera prior.
TEST(Pccs, SceneDepthPriorSpansBothCamerasFloors) {
  const SceneDepthPrior same = scene_depth_prior(4.0, 4.5, -0.5, 0.1, 0.5);
  EXPECT_NEAR(same.depth_m, 4.0, 1e-12);
  EXPECT_NEAR(same.sigma_m, 0.1 * 4.0 + 0.5, 1e-12);
  // Camera i above a hull's edge sees mud 12 m down; camera j, 1 m higher, the deck 5 m below
  // it: 4 m along camera i's axis.
  const SceneDepthPrior edge = scene_depth_prior(12.0, 5.0, -1.0, 0.1, 0.5);
  for (const double d : {4.0, 12.0}) {
    const double sigma_d = 0.1 * d + 0.5;
    EXPECT_LE(edge.depth_m - 3.0 * edge.sigma_m, d - 3.0 * sigma_d + 1e-9) << d;
    EXPECT_GE(edge.depth_m + 3.0 * edge.sigma_m, d + 3.0 * sigma_d - 1e-9) << d;
  }
  EXPECT_LT(edge.depth_m - 3.0 * edge.sigma_m, 4.0);
}

}  // namespace
}  // namespace nav::vision
