// g2o reader, information conversion and information assembly (posegraph/g2o.h).

#include "nav/core/posegraph/g2o.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "nav/core/geometry/pose.h"
#include "nav/core/geometry/rotation.h"
#include "nav/testing/data.h"
#include "nav/testing/numeric_jacobian.h"

namespace nav::core {
namespace {

using nav::testing::max_abs_diff;
using nav::testing::numeric_jacobian;

constexpr double kPi = std::numbers::pi;

const std::string kIdentityInfo = " 1 0 0 0 0 0  1 0 0 0 0  1 0 0 0  1 0 0  1 0  1";

PoseGraph parse(const std::string& text) {
  std::istringstream in(text);
  return read_g2o(in, "test.g2o");
}

/// Expects read_g2o to throw G2oError whose message starts with "test.g2o:<line>:" and
/// contains `reason`.
void expect_error(const std::string& text, int line, const std::string& reason) {
  try {
    parse(text);
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const G2oError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.line(), line) << what;
    EXPECT_EQ(what.rfind("test.g2o:" + std::to_string(line) + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(reason), std::string::npos) << "'" << what << "' lacks '" << reason << "'";
  }
}

Eigen::Quaterniond quaternion_of(const Vec3& rpy) {
  return Eigen::Quaterniond(rotation_from_euler(rpy));
}

std::string vertex_line(int id, const Vec6& pose) {
  const Eigen::Quaterniond q = quaternion_of(pose.tail<3>());
  std::ostringstream s;
  s.precision(17);
  s << "VERTEX_SE3:QUAT " << id << " " << pose[0] << " " << pose[1] << " " << pose[2] << " "
    << q.x() << " " << q.y() << " " << q.z() << " " << q.w() << "\n";
  return s.str();
}

TEST(G2o, VertexQuaternionBecomesZyxEuler) {
  // 90 deg heading: q = (cos 45, 0, 0, sin 45).
  const double h = std::sqrt(0.5);
  const PoseGraph g =
      parse("VERTEX_SE3:QUAT 0 1 2 3 0 0 " + std::to_string(h) + " " + std::to_string(h) + "\n");
  ASSERT_EQ(g.vertices.size(), 1u);
  EXPECT_NEAR(g.vertices[0].pose[0], 1.0, 0);
  EXPECT_NEAR(g.vertices[0].pose[2], 3.0, 0);
  EXPECT_NEAR(g.vertices[0].pose[kRoll], 0.0, 1e-6);
  EXPECT_NEAR(g.vertices[0].pose[kPitch], 0.0, 1e-6);
  EXPECT_NEAR(g.vertices[0].pose[kHeading], kPi / 2, 1e-6);

  // A general rotation round-trips through the quaternion.
  const Vec6 pose = (Vec6() << -4, 5, 6, 0.3, -0.7, 2.5).finished();
  const PoseGraph g2 = parse(vertex_line(3, pose));
  EXPECT_LT(max_abs_diff(g2.vertices[0].pose, pose), 1e-12);
}

TEST(G2o, InformationJacobianMatchesG2oErrorNumerically) {
  // g2o EdgeSE3: e(y) = [t(Z^-1 Y); vec(q(Z^-1 Y)), w >= 0] for Y the relative pose with our
  // parameters y; G = de/dy at y = z.
  const Vec6 z = (Vec6() << 1.0, -2.0, 0.5, 0.4, -0.3, 1.2).finished();
  const auto iso = [](const Eigen::VectorXd& y) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = rotation_from_euler(y.tail<3>());
    T.translation() = y.head<3>();
    return T;
  };
  const Eigen::Isometry3d Z = iso(z);
  const auto error = [&](const Eigen::VectorXd& y) {
    const Eigen::Isometry3d delta = Z.inverse() * iso(y);
    Eigen::Quaterniond q(delta.linear());
    if (q.w() < 0) q.coeffs() *= -1.0;
    Eigen::VectorXd e(6);
    e << delta.translation(), q.vec();
    return e;
  };
  const Eigen::MatrixXd numeric = numeric_jacobian(error, z);
  EXPECT_LT(max_abs_diff(g2o_error_jacobian(z), numeric), 1e-8) << numeric;
}

TEST(G2o, EdgeInformationIsConvertedToEulerParameters) {
  const Vec6 x0 = Vec6::Zero();
  const Vec6 x1 = (Vec6() << 1, 0.2, -0.1, 0.1, 0.05, 0.3).finished();
  const Eigen::Quaterniond q = quaternion_of(x1.tail<3>());
  std::ostringstream edge;
  edge.precision(17);
  edge << "EDGE_SE3:QUAT 0 1 1 0.2 -0.1 " << q.x() << " " << q.y() << " " << q.z() << " " << q.w()
       << " 100 0 0 0 0 0 100 0 0 0 0 100 0 0 0 400 0 0 400 0 400\n";
  const PoseGraph g = parse(vertex_line(0, x0) + vertex_line(1, x1) + edge.str());
  ASSERT_EQ(g.edges.size(), 1u);
  const G2oEdge& e = g.edges[0];
  EXPECT_EQ(e.line, 3);
  EXPECT_LT(max_abs_diff(e.measurement, x1), 1e-12);
  Mat6 omega_g2o = Mat6::Zero();
  omega_g2o.diagonal() << 100, 100, 100, 400, 400, 400;
  EXPECT_EQ(max_abs_diff(e.information_g2o, omega_g2o), 0.0);
  const Mat6 G = g2o_error_jacobian(x1);
  EXPECT_LT(max_abs_diff(e.information, G.transpose() * omega_g2o * G), 1e-9);
  // Rotation information 400 on qvec ~ theta/2 is 100 on theta: at zero angles the converted
  // information is diag(100, 100, 100, 100, 100, 100).
  const PoseGraph g0 = parse(vertex_line(0, x0) + vertex_line(1, x0) +
                             "EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1 100 0 0 0 0 0 100 0 0 0 0 100 0 0 0 "
                             "400 0 0 400 0 400\n");
  EXPECT_LT(max_abs_diff(g0.edges[0].information, Mat6::Identity() * 100.0), 1e-12);
}

TEST(G2o, NonContiguousIdsAreRemappedInIdOrder) {
  const PoseGraph g = parse("# comment\n\n" + vertex_line(10, Vec6::Zero()) +
                            vertex_line(5, Vec6::Zero()) + vertex_line(7, Vec6::Zero()) +
                            "EDGE_SE3:QUAT 10 5 0 0 0 0 0 0 1" + kIdentityInfo + "\n");
  ASSERT_EQ(g.vertices.size(), 3u);
  EXPECT_EQ(g.vertices[0].id, 5);
  EXPECT_EQ(g.vertices[1].id, 7);
  EXPECT_EQ(g.vertices[2].id, 10);
  ASSERT_EQ(g.edges.size(), 1u);
  EXPECT_EQ(g.edges[0].from, 10);
  EXPECT_EQ(g.edges[0].to, 5);
  EXPECT_EQ(g.edges[0].from_index, 2);
  EXPECT_EQ(g.edges[0].to_index, 0);
  EXPECT_EQ(g.edges[0].line, 6);
}

TEST(G2o, QuaternionCloseToUnitIsNormalised) {
  const PoseGraph g = parse("VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1.0005\n");
  EXPECT_LT(g.vertices[0].pose.cwiseAbs().maxCoeff(), 1e-15);
}

TEST(G2o, MalformedInputNamesLineAndReason) {
  const std::string v0 = "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n";
  const std::string v1 = "VERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n";
  expect_error(v0 + "VERTEX_XY 1 0 0\n", 2, "unknown tag 'VERTEX_XY'");
  expect_error(v0 + "VERTEX_SE2 1 0 0 0\n", 2,
               "planar (SE2) element in a file whose line 1 is 3-D (SE3)");
  expect_error("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 0\n", 2, "has 4 fields, expected 5");
  expect_error("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 0 0\nEDGE_SE2 0 1 0 0 0 1 0 0 -1 0 1\n", 3,
               "not positive definite");
  expect_error(v0 + "FIX\n", 2, "FIX names no vertex");
  expect_error(v0 + "FIX 0 x\n", 2, "non-integer vertex id 'x'");
  expect_error("VERTEX_SE3:QUAT 0 0 0 0 0 0 1\n", 1, "has 8 fields, expected 9");
  expect_error(v0 + v1 + "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 1 0 0\n", 3, "expected 31");
  expect_error("VERTEX_SE3:QUAT 0 0 abc 0 0 0 0 1\n", 1, "non-numeric y 'abc'");
  expect_error("VERTEX_SE3:QUAT 0 0 1e5x 0 0 0 0 1\n", 1, "non-numeric y");
  expect_error("VERTEX_SE3:QUAT 0 nan 0 0 0 0 0 1\n", 1, "non-finite x");
  expect_error("VERTEX_SE3:QUAT 0 0 0 inf 0 0 0 1\n", 1, "non-finite z");
  expect_error("VERTEX_SE3:QUAT 0 0 0 1e999 0 0 0 1\n", 1, "non-finite z");
  expect_error("VERTEX_SE3:QUAT x 0 0 0 0 0 0 1\n", 1, "non-integer vertex id 'x'");
  expect_error("VERTEX_SE3:QUAT -3 0 0 0 0 0 0 1\n", 1, "out of range");
  expect_error("VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1.01\n", 1, "quaternion norm");
  expect_error("VERTEX_SE3:QUAT 0 0 0 0 0 0 0 0\n", 1, "quaternion norm 0");
  expect_error(v0 + v1 + v0, 3, "duplicate vertex 0 (first defined on line 1)");
  expect_error(v0 + v1 + "EDGE_SE3:QUAT 0 2 0 0 0 0 0 0 1" + kIdentityInfo + "\n", 3,
               "edge to unknown vertex 2");
  expect_error(v0 + v1 + "EDGE_SE3:QUAT 4 1 0 0 0 0 0 0 1" + kIdentityInfo + "\n", 3,
               "edge from unknown vertex 4");
  expect_error(v0 + "EDGE_SE3:QUAT 0 0 0 0 0 0 0 0 1" + kIdentityInfo + "\n", 2,
               "edge from vertex 0 to itself");
  // Indefinite information (I11 = -1) and a singular one (all zero).
  expect_error(
      v0 + v1 + "EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1 -1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n", 3,
      "not positive definite");
  expect_error(
      v0 + v1 + "EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n", 3,
      "not positive definite");
  // Errors on an edge line are reported even when the vertex appears later in the file.
  expect_error(v0 + "EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1" + kIdentityInfo + "\n" + "\n" + v1 +
                   "EDGE_SE3:QUAT 0 9 0 0 0 0 0 0 1" + kIdentityInfo + "\n",
               5, "edge to unknown vertex 9");
}

TEST(G2o, FixLinesAreReadAndTheGaugeStaysThePriorOnVertexZero) {
  const PoseGraph g =
      parse("FIX 1\n" + vertex_line(0, Vec6::Zero()) + vertex_line(1, Vec6::Ones() * 0.1));
  EXPECT_EQ(g.vertices.size(), 2u);
  EXPECT_FALSE(g.planar);
}

/// g2o's SE2 pose (x, y, theta) as a homogeneous 3x3 transform, and its inverse's product.
Eigen::Matrix3d se2(const Eigen::Vector3d& p) {
  Eigen::Matrix3d T = Eigen::Matrix3d::Identity();
  T.topLeftCorner<2, 2>() = Eigen::Rotation2Dd(p[2]).toRotationMatrix();
  T.topRightCorner<2, 1>() = p.head<2>();
  return T;
}
Eigen::Vector3d se2_vector(const Eigen::Matrix3d& T) {
  return {T(0, 2), T(1, 2), std::atan2(T(1, 0), T(0, 0))};
}

struct PlanarEdge {
  int i, j;
  Eigen::Matrix3d information;
};

TEST(G2o, PlanarGraphIsLiftedTo3D) {
  const PoseGraph g = parse(
      "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 2 3.5\n"
      "EDGE_SE2 0 1 1 2 0.5 100 10 5 200 -4 50\n");
  ASSERT_TRUE(g.planar);
  ASSERT_EQ(g.vertices.size(), 2u);
  EXPECT_LT(max_abs_diff(g.vertices[1].pose, (Vec6() << 1, 2, 0, 0, 0, 3.5 - 2 * kPi).finished()),
            1e-12);
  const G2oEdge& e = g.edges[0];
  EXPECT_LT(max_abs_diff(e.measurement, (Vec6() << 1, 2, 0, 0, 0, 0.5).finished()), 1e-15);
  // The in-plane information on [t_ij; heading_ij]: g2o's EdgeSE2 error is
  // [R(0.5)ᵀ (t - t_z); theta - theta_z], so Omega_y = Gᵀ Omega_2 G with G = diag(R(0.5)ᵀ, 1).
  Eigen::Matrix3d omega2;
  omega2 << 100, 10, 5, 10, 200, -4, 5, -4, 50;
  Eigen::Matrix3d G = Eigen::Matrix3d::Identity();
  G.topLeftCorner<2, 2>() = Eigen::Rotation2Dd(0.5).toRotationMatrix().transpose();
  const Eigen::Matrix3d expected = G.transpose() * omega2 * G;
  constexpr int kIn[3] = {0, 1, 5};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(e.information(kIn[r], kIn[c]), expected(r, c), 1e-9);
  }
  // Out of plane: z with the mean x/y information, roll and pitch with theta's, uncorrelated.
  EXPECT_NEAR(e.information(2, 2), 150.0, 1e-9);
  EXPECT_NEAR(e.information(3, 3), 50.0, 1e-9);
  EXPECT_NEAR(e.information(4, 4), 50.0, 1e-9);
  for (int in : kIn) {
    for (int out : {2, 3, 4}) EXPECT_NEAR(e.information(in, out), 0.0, 1e-9);
  }
}

TEST(G2o, LiftedPlanarMarginalsEqualThePlanarGraphs) {
  // A loop of five poses with a closure and a cross edge; measurements consistent with the
  // poses, so both linearisations below are at the measurement.
  const std::vector<Eigen::Vector3d> poses = {
      {0, 0, 0}, {2, 0.3, 0.6}, {3, 2, 1.9}, {1, 3, -2.8}, {-0.5, 1.5, -1.4}};
  Eigen::Matrix3d a, b;
  a << 400, 30, -20, 30, 250, 10, -20, 10, 900;
  b << 90, -5, 3, -5, 60, 1, 3, 1, 300;
  const std::vector<PlanarEdge> edges = {{0, 1, a}, {1, 2, b}, {2, 3, a},
                                         {3, 4, b}, {4, 0, a}, {1, 3, b}};
  std::ostringstream text;
  text.precision(17);
  for (size_t k = 0; k < poses.size(); ++k) {
    text << "VERTEX_SE2 " << k << " " << poses[k].transpose() << "\n";
  }
  for (const PlanarEdge& e : edges) {
    const Eigen::Matrix3d& I = e.information;
    text << "EDGE_SE2 " << e.i << " " << e.j << " "
         << se2_vector(se2(poses[e.i]).inverse() * se2(poses[e.j])).transpose() << " " << I(0, 0)
         << " " << I(0, 1) << " " << I(0, 2) << " " << I(1, 1) << " " << I(1, 2) << " " << I(2, 2)
         << "\n";
  }
  const PoseGraph g = parse(text.str());
  const Eigen::MatrixXd lifted_cov = Eigen::MatrixXd(assemble_information_sparse(g)).inverse();

  // Reference: the planar graph in g2o's own terms, Λ = P + Σ Jᵀ Ω₂ J with J the numeric
  // Jacobian of EdgeSE2's error toVector(Z⁻¹ X_i⁻¹ X_j) and P the in-plane part of the prior.
  const Eigen::Index n = static_cast<Eigen::Index>(poses.size()) * 3;
  Eigen::MatrixXd planar = Eigen::MatrixXd::Zero(n, n);
  planar.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * 1e6;
  for (const PlanarEdge& e : edges) {
    const Eigen::Matrix3d Z_inv = (se2(poses[e.i]).inverse() * se2(poses[e.j])).inverse();
    const auto error = [&](const Eigen::VectorXd& x) {
      return Eigen::VectorXd(se2_vector(Z_inv * se2(x.head<3>()).inverse() * se2(x.tail<3>())));
    };
    Eigen::VectorXd x(6);
    x << poses[e.i], poses[e.j];
    const Eigen::MatrixXd J = numeric_jacobian(error, x, 1e-6);
    const Eigen::MatrixXd JtOJ = J.transpose() * e.information * J;
    const Eigen::Index ai = 3 * e.i, aj = 3 * e.j;
    planar.block(ai, ai, 3, 3) += JtOJ.topLeftCorner(3, 3);
    planar.block(aj, aj, 3, 3) += JtOJ.bottomRightCorner(3, 3);
    planar.block(ai, aj, 3, 3) += JtOJ.topRightCorner(3, 3);
    planar.block(aj, ai, 3, 3) += JtOJ.bottomLeftCorner(3, 3);
  }
  const Eigen::MatrixXd planar_cov = planar.inverse();
  constexpr int kIn[3] = {0, 1, 5};
  for (Eigen::Index v = 0; v < static_cast<Eigen::Index>(poses.size()); ++v) {
    for (Eigen::Index w = 0; w < static_cast<Eigen::Index>(poses.size()); ++w) {
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
          const double ref = planar_cov(3 * v + r, 3 * w + c);
          const double got = lifted_cov(6 * v + kIn[r], 6 * w + kIn[c]);
          EXPECT_NEAR(got, ref, 1e-6 * planar_cov.cwiseAbs().maxCoeff())
              << "vertices " << v << ", " << w << " entry " << r << ", " << c;
        }
        for (int out : {2, 3, 4}) {  // in-plane and out-of-plane uncorrelated
          EXPECT_NEAR(lifted_cov(6 * v + kIn[r], 6 * w + out), 0.0,
                      1e-9 * lifted_cov.cwiseAbs().maxCoeff());
        }
      }
    }
  }
}

TEST(G2o, MissingFileIsAnError) { EXPECT_THROW(read_g2o("/nonexistent/graph.g2o"), G2oError); }

TEST(G2o, ReadsThePublicGraphs) {
  NAV_REQUIRE_DATA(tiny, "posegraphs/tinyGrid3D.g2o");
  NAV_REQUIRE_DATA(small, "posegraphs/smallGrid3D.g2o");
  NAV_REQUIRE_DATA(garage, "posegraphs/parking-garage.g2o");
  NAV_REQUIRE_DATA(sphere, "posegraphs/sphere2500.g2o");
  struct Expect {
    std::filesystem::path path;
    size_t vertices, edges;
  };
  for (const Expect& e : {Expect{tiny, 9, 11}, Expect{small, 125, 297}, Expect{garage, 1661, 6275},
                          Expect{sphere, 2500, 4949}}) {
    const PoseGraph g = read_g2o(e.path.string());
    EXPECT_EQ(g.vertices.size(), e.vertices) << e.path;
    EXPECT_EQ(g.edges.size(), e.edges) << e.path;
    for (size_t k = 0; k < g.vertices.size(); ++k) {
      ASSERT_EQ(g.vertices[k].id, static_cast<int>(k)) << e.path << ": ids are 0..N-1 in order";
    }
  }
}

/// Lambda built independently: numeric tail_to_tail Jacobians, dense accumulation.
Eigen::MatrixXd numeric_information(const PoseGraph& g, const Mat6& prior) {
  const Eigen::Index n = static_cast<Eigen::Index>(g.vertices.size()) * 6;
  Eigen::MatrixXd Lambda = Eigen::MatrixXd::Zero(n, n);
  Lambda.topLeftCorner<6, 6>() += prior;
  const auto minus = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return Eigen::VectorXd(pose_minus(a, b));
  };
  for (const G2oEdge& e : g.edges) {
    Eigen::VectorXd x(12);
    x << g.vertices[static_cast<size_t>(e.from_index)].pose,
        g.vertices[static_cast<size_t>(e.to_index)].pose;
    const auto f = [](const Eigen::VectorXd& v) {
      return Eigen::VectorXd(tail_to_tail(v.head<6>(), v.tail<6>()));
    };
    const Eigen::MatrixXd H = numeric_jacobian(f, x, 1e-6, minus);
    const Eigen::MatrixXd HtOH = H.transpose() * e.information * H;
    const Eigen::Index a = e.from_index * 6, b = e.to_index * 6;
    Lambda.block(a, a, 6, 6) += HtOH.topLeftCorner(6, 6);
    Lambda.block(b, b, 6, 6) += HtOH.bottomRightCorner(6, 6);
    Lambda.block(a, b, 6, 6) += HtOH.topRightCorner(6, 6);
    Lambda.block(b, a, 6, 6) += HtOH.bottomLeftCorner(6, 6);
  }
  return Lambda;
}

TEST(G2o, AssembledInformationMatchesNumericJacobians) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  const PoseGraph g = read_g2o(path.string());
  AssemblyOptions options;
  options.prior_information = Mat6::Identity() * 1e4;
  const Eigen::MatrixXd sparse = Eigen::MatrixXd(assemble_information_sparse(g, options));
  const Eigen::MatrixXd expected = numeric_information(g, options.prior_information);
  const double scale = expected.cwiseAbs().maxCoeff();
  EXPECT_LT(max_abs_diff(sparse, expected), 1e-6 * scale);
  EXPECT_LT(max_abs_diff(sparse, sparse.transpose()), 1e-12 * scale);
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(sparse).info(), Eigen::Success) << "Lambda not SPD";

  const InformationMatrix blocks = assemble_information(g, options);
  EXPECT_EQ(blocks.block_dim(), 6);
  EXPECT_EQ(blocks.num_blocks(), 125);
  EXPECT_LT(max_abs_diff(blocks.to_dense(), sparse), 1e-12 * scale);
}

TEST(G2o, WithoutPriorTheInformationIsSingular) {
  NAV_REQUIRE_DATA(path, "posegraphs/tinyGrid3D.g2o");
  const PoseGraph g = read_g2o(path.string());
  AssemblyOptions options;
  options.prior_information.setZero();
  const Eigen::MatrixXd Lambda(assemble_information_sparse(g, options));
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Lambda);
  // Six gauge directions: the whole graph moved rigidly changes no relative pose.
  EXPECT_LT(eig.eigenvalues()[5], 1e-8 * eig.eigenvalues().maxCoeff());
  EXPECT_GT(eig.eigenvalues()[6], 1e-6 * eig.eigenvalues().maxCoeff());
}

}  // namespace
}  // namespace nav::core
