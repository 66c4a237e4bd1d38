// The default mission is the paper's survey in size (866 images, ~3 km of track, convex hull
// ~3,100 m^2), flown at a safe altitude over a ~10 m wreck at ~3,800 m; its pieces (planar
// geometry, seafloor, guidance) behave as documented.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "nav/sim/geometry2d.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

TEST(SimMission, DefaultDiveIsThePapersSurveyInSize) {
  SimOptions o;
  o.out_dir = scratch_dir("default").string();
  const auto start = std::chrono::steady_clock::now();
  const SimSummary s = simulate_dive(o, sim_config_path().string());
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "default dive: %lld images, %.0f s, track %.1f m, hull %.1f m^2, altitude "
      "%.2f/%.2f/%.2f m, %lld registrations (%lld ok, %lld outliers), %.2f s wall\n",
      static_cast<long long>(s.images), s.duration_s, s.track_length_m, s.survey_hull_area_m2,
      s.min_altitude_m, s.mean_altitude_m, s.max_altitude_m,
      static_cast<long long>(s.registrations), static_cast<long long>(s.registrations_succeeded),
      static_cast<long long>(s.outliers_injected), wall_s);
  EXPECT_EQ(s.images, 866);
  EXPECT_NEAR(s.track_length_m, 3000.0, 300.0);
  EXPECT_NEAR(s.survey_hull_area_m2, 3100.0, 300.0);
  EXPECT_NEAR(s.duration_s, 866 * 8.0, 0.1 * 866 * 8.0);
  EXPECT_GT(s.min_altitude_m, 3.0) << "the vehicle keeps clear of the wreck";
  EXPECT_LT(s.mean_altitude_m, 8.0);
  EXPECT_GT(s.first_frame_after_transit, 400);
  EXPECT_LT(s.first_frame_after_transit, 470);
  EXPECT_EQ(s.sensors.dvl_ensembles, s.sensors.altimeter_lines + 1);  // 5 Hz both, offset 100 ms
  EXPECT_GT(s.sensors.dvl_invalid_ensembles, 3 * 10 * 5 - 1) << "three dropouts of >= 10 s";
}

TEST(SimMission, BadOptionsAreRejectedNamingTheField) {
  auto message_of = [](const SimOptions& o) {
    try {
      simulate_dive(o, sim_config_path().string());
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  SimOptions o;
  o.out_dir = scratch_dir("bad").string();
  o.oracle.outlier_rate = 1.5;
  EXPECT_NE(message_of(o).find("SimOptions.oracle.outlier_rate"), std::string::npos)
      << message_of(o);
  o.oracle.outlier_rate = 0.05;
  o.sensor_errors.jitter_ms = -1.0;
  EXPECT_NE(message_of(o).find("SimOptions.sensor_errors.jitter_ms"), std::string::npos);
  o.sensor_errors.jitter_ms = 2.0;
  o.mission.images = 1;
  EXPECT_NE(message_of(o).find("MissionOptions.images"), std::string::npos);
  o.mission.images = 10;
  daemon::NavdConfig no_camera = daemon::load_config_file(sim_config_path().string());
  no_camera.sensors.pop_back();
  try {
    simulate_dive(o, no_camera, "");
    ADD_FAILURE() << "a config without a camera was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("camera"), std::string::npos) << e.what();
  }
}

TEST(SimMission, ConvexGeometry) {
  const Polygon2 square{{0, 0}, {2, 0}, {2, 2}, {0, 2}};
  const Polygon2 shifted{{1, 1}, {3, 1}, {3, 3}, {1, 3}};
  EXPECT_DOUBLE_EQ(area_m2(square), 4.0);
  EXPECT_NEAR(area_m2(intersect_convex(square, shifted)), 1.0, 1e-12);
  const Polygon2 clockwise(shifted.rbegin(), shifted.rend());
  EXPECT_NEAR(area_m2(intersect_convex(clockwise, square)), 1.0, 1e-12);
  EXPECT_TRUE(intersect_convex(square, {{5, 5}, {6, 5}, {6, 6}}).empty());
  const Polygon2 hull = convex_hull({{0, 0}, {1, 0.5}, {2, 0}, {2, 2}, {1, 1}, {0, 2}});
  EXPECT_EQ(hull.size(), 4u);
  EXPECT_DOUBLE_EQ(area_m2(hull), 4.0);
}

TEST(SimMission, SeafloorHasAWreckAtDepth) {
  const GridExtent e{-40.0, 40.0, -20.0, 60.0};
  const Seafloor a(e, 0.0, 20.0, {}, 3), b(e, 0.0, 20.0, {}, 3), c(e, 0.0, 20.0, {}, 4);
  EXPECT_NEAR(a.depth_m(0.0, -15.0), 3800.0, 3.0);  // the mud beside the wreck
  std::vector<double> deck;                         // open deck beside the deckhouses, ~10 m proud
  for (double x = -8.0; x < -4.0; x += 0.1)
    for (double y = 10.0; y < 12.0; y += 0.1) deck.push_back(a.relief_height_m(x, y));
  std::nth_element(deck.begin(), deck.begin() + deck.size() / 2, deck.end());
  EXPECT_NEAR(deck[deck.size() / 2], 10.0, 0.5);
  EXPECT_LT(std::abs(a.relief_height_m(0.0, -15.0)), 1.0);
  double differs = 0.0;
  for (double x = -30; x < 30; x += 0.7) {
    for (double y = -10; y < 50; y += 0.7) {
      EXPECT_EQ(a.depth_m(x, y), b.depth_m(x, y));
      differs = std::max(differs, std::abs(a.depth_m(x, y) - c.depth_m(x, y)));
      EXPECT_LE(a.safe_depth_m(x, y), a.depth_m(x, y) + 1e-3) << "safe depth above the floor";
    }
  }
  EXPECT_GT(differs, 0.1) << "another seed, another debris field";
}

TEST(SimMission, PlanAndGuidanceFollowTheLines) {
  MissionOptions o;
  o.images = 100;
  const Mission m = plan_mission(o);
  ASSERT_GT(m.waypoints.size(), 4u);
  EXPECT_EQ(m.waypoints[0].x_m, 0.0);
  EXPECT_EQ(m.waypoints[1].y_m, o.line_length_m);
  EXPECT_FALSE(m.waypoints[m.transit_end].camera_on);
  Guidance g(m);
  const Guidance::Command c = g.update(0.0, 0.0);
  EXPECT_NEAR(c.heading_rad, M_PI / 2.0, 1e-12);  // east along the first line
  EXPECT_TRUE(c.camera_on);
  EXPECT_NEAR(g.update(0.5, 10.0).heading_rad, M_PI / 2.0 + std::atan(0.5 / 2.0), 1e-12);
  g.request_transit();
  const Guidance::Command t = g.update(0.0, o.line_length_m + 0.1);  // end of line 0
  EXPECT_FALSE(t.camera_on);
  EXPECT_EQ(g.segment(), static_cast<int>(m.transit_end) - 1);
  MissionOptions bad;
  bad.speed_mps = 0.0;
  EXPECT_THROW(plan_mission(bad), std::invalid_argument);
}

}  // namespace
}  // namespace nav::sim::test
