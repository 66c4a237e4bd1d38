// navtool topside's converters against hand-built messages and independent references:
// ellipses against covariances built as R diag(a^2, b^2) R^T, the Foxglove quaternion against
// Eigen's AngleAxis composition, the message-data frame byte by byte, and the bounded queue.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "nav/daemon/topside/client_queue.h"
#include "nav/daemon/topside/ellipse.h"
#include "nav/daemon/topside/foxglove.h"
#include "nav/daemon/topside/lcm_json.h"

namespace nav::daemon::topside {
namespace {

TEST(TopsideEllipse, RecoversAxesAndAngleOfRotatedCovariance) {
  for (const double angle : {-1.2, -0.3, 0.0, 0.4, 1.1}) {
    const double a = 2.0, b = 0.5;
    const Eigen::Matrix2d R = Eigen::Rotation2Dd(angle).toRotationMatrix();
    const Eigen::Matrix2d P = R * Eigen::Vector2d(a * a, b * b).asDiagonal() * R.transpose();
    const Ellipse2 e = covariance_ellipse(P(0, 0), P(0, 1), P(1, 1), 3.0);
    EXPECT_NEAR(e.semi_major_m, 3.0 * a, 1e-12);
    EXPECT_NEAR(e.semi_minor_m, 3.0 * b, 1e-12);
    EXPECT_NEAR(e.angle_rad, angle, 1e-12) << angle;
  }
}

TEST(TopsideEllipse, EllipsoidAxesAreEigenvaluesAndRotationMapsThem) {
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  const Eigen::Matrix3d P = R * Eigen::Vector3d(0.01, 0.25, 4.0).asDiagonal() * R.transpose();
  std::array<double, 9> p{};
  Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(p.data()) = P;
  const Ellipsoid3 e = covariance_ellipsoid(p, 3.0);
  // Reconstruct P from the ellipsoid: Q diag((size/2k)^2) Q^T.
  const Eigen::Quaterniond q(e.q_xyzw[3], e.q_xyzw[0], e.q_xyzw[1], e.q_xyzw[2]);
  Eigen::Vector3d l;
  for (int i = 0; i < 3; ++i) l[i] = std::pow(e.size_m[i] / 6.0, 2);
  const Eigen::Matrix3d back = q.toRotationMatrix() * l.asDiagonal() * q.toRotationMatrix().transpose();
  EXPECT_LT((back - P).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(e.size_m[2], 6.0 * 2.0, 1e-12);  // ascending eigenvalues: sqrt(4) * 2 * 3
}

navlcm::nav_solution_t solution() {
  navlcm::nav_solution_t m{};
  m.utime = 1'700'000'000'123'456;
  m.p_world_m[0] = 10.0;
  m.p_world_m[1] = -4.0;
  m.p_world_m[2] = 37.25;
  m.rph_rad[0] = 0.05;
  m.rph_rad[1] = -0.1;
  m.rph_rad[2] = 2.5;
  m.v_body_mps[0] = 0.3;
  m.v_body_mps[1] = 0.4;
  m.pose_covariance[0] = 4.0;   // x
  m.pose_covariance[7] = 1.0;   // y
  m.pose_covariance[14] = 0.09; // z
  m.num_delayed_states = 7;
  m.num_camera_links = 3;
  m.filter_status = 1;
  return m;
}

TEST(TopsideJson, SolutionCarriesFieldsAndDerivedDisplayValues) {
  const nlohmann::json j = to_json(solution());
  EXPECT_EQ(j["utime"], 1'700'000'000'123'456);
  EXPECT_DOUBLE_EQ(j["depth_m"].get<double>(), 37.25);
  EXPECT_DOUBLE_EQ(j["p_world_m"][1].get<double>(), -4.0);
  EXPECT_DOUBLE_EQ(j["heading_rad"].get<double>(), 2.5);
  EXPECT_DOUBLE_EQ(j["speed_mps"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j["sigma_xy_m"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(j["sigma_z_m"].get<double>(), 0.3);
  EXPECT_EQ(j["num_delayed_states"], 7);
  EXPECT_EQ(j["num_camera_links"], 3);
  EXPECT_EQ(j["filter_status"], 1);
  EXPECT_EQ(j["pose_covariance"].size(), 36u);
}

TEST(TopsideJson, HealthRowsAndBoundEllipse) {
  navlcm::health_t h{};
  h.status = "ok";
  h.queue_depth = 3;
  navlcm::sensor_health_t s{};
  s.name = "dvl";
  s.rate_hz = 5.0;
  s.connected = 1;
  s.last_message_age_s = 0.2;
  s.nis_mean = 2.9;
  s.nis_expected = 3.0;
  navlcm::aid_source_t a{};
  a.innovation = 0.01;
  a.fused = 1;
  s.last.push_back(a);
  s.num_components = 1;
  h.sensors.push_back(s);
  h.num_sensors = 1;
  const nlohmann::json j = to_json(h);
  ASSERT_EQ(j["sensors"].size(), 1u);
  EXPECT_EQ(j["sensors"][0]["name"], "dvl");
  EXPECT_EQ(j["sensors"][0]["connected"], true);
  EXPECT_DOUBLE_EQ(j["sensors"][0]["nis_mean"].get<double>(), 2.9);
  EXPECT_EQ(j["sensors"][0]["last"][0]["fused"], true);
  EXPECT_EQ(j["queue_depth"], 3);

  navlcm::delayed_state_bound_t b{};
  b.state_id = 42;
  b.mean_pose[0] = 1.0;
  b.bound_covariance[0] = 0.25;
  b.bound_covariance[7] = 0.04;
  const nlohmann::json jb = to_json(b);
  EXPECT_EQ(jb["state_id"], 42);
  EXPECT_DOUBLE_EQ(jb["ellipse_3sigma"]["semi_major_m"].get<double>(), 1.5);
  EXPECT_NEAR(jb["ellipse_3sigma"]["semi_minor_m"].get<double>(), 0.6, 1e-15);
}

TEST(TopsideFoxglove, PoseQuaternionMatchesZyxComposition) {
  const navlcm::nav_solution_t m = solution();
  const nlohmann::json p = pose_in_frame(m);
  const Eigen::Quaterniond ref = Eigen::AngleAxisd(m.rph_rad[2], Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(m.rph_rad[1], Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(m.rph_rad[0], Eigen::Vector3d::UnitX());
  const auto& q = p["pose"]["orientation"];
  EXPECT_NEAR(q["x"].get<double>(), ref.x(), 1e-12);
  EXPECT_NEAR(q["y"].get<double>(), ref.y(), 1e-12);
  EXPECT_NEAR(q["z"].get<double>(), ref.z(), 1e-12);
  EXPECT_NEAR(q["w"].get<double>(), ref.w(), 1e-12);
  EXPECT_EQ(p["timestamp"]["sec"], 1'700'000'000);
  EXPECT_EQ(p["timestamp"]["nsec"], 123'456'000);
  EXPECT_DOUBLE_EQ(p["pose"]["position"]["z"].get<double>(), 37.25);
}

TEST(TopsideFoxglove, MessageDataFrameIsOpcodeSubscriptionTimeLittleEndianThenPayload) {
  const std::string f = message_data_frame(0x01020304u, 0x1122334455667788ull, "{}");
  const std::string expected("\x01\x04\x03\x02\x01\x88\x77\x66\x55\x44\x33\x22\x11{}", 15);
  EXPECT_EQ(f, expected);
}

TEST(TopsideFoxglove, LinkLineNeedsBothStatesAndColoursByKind) {
  navlcm::camera_link_t l{};
  l.state_id_i = 1;
  l.state_id_j = 5;
  l.accepted = 1;
  std::map<std::int64_t, std::array<double, 3>> pos{{1, {0, 0, 0}}};
  EXPECT_TRUE(link_scene_update(l, pos, false)["entities"].empty());
  pos[5] = {3, 4, 0};
  const nlohmann::json loop = link_scene_update(l, pos, false);
  ASSERT_EQ(loop["entities"].size(), 1u);
  EXPECT_EQ(loop["entities"][0]["id"], "link/1-5");
  EXPECT_DOUBLE_EQ(loop["entities"][0]["lines"][0]["points"][1]["y"].get<double>(), 4.0);
  const nlohmann::json temporal = link_scene_update(l, pos, true);
  EXPECT_NE(loop["entities"][0]["lines"][0]["color"], temporal["entities"][0]["lines"][0]["color"]);
}

TEST(TopsideClientQueue, DropsOldestWhenFullAndCountsDrops) {
  ClientQueue q(2);
  for (int i = 0; i < 5; ++i) q.push({std::make_shared<const std::string>(std::to_string(i)), false});
  EXPECT_EQ(q.queued(), 2u);
  EXPECT_EQ(q.dropped(), 3u);
  EXPECT_EQ(*q.pop().payload, "3");
  EXPECT_EQ(*q.pop().payload, "4");
  EXPECT_FALSE(q.has_frames());
  EXPECT_THROW(ClientQueue(0), std::invalid_argument);
}

}  // namespace
}  // namespace nav::daemon::topside
