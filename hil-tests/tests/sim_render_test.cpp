// --render-images: 16-bit PNG frames with 12 significant bits beside the log, referenced by
// NAV_IMAGE with an 8-bit thumbnail; the renderer is deterministic, textured, and strobe-lit
// (brighter in the middle than in the corners over a flat floor); its texture is filtered by
// the pixel's footprint; two frames' visible overlap over a flat floor is their flat footprints'
// overlap, and none beyond the camera's range.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <variant>

#include "nav/sim/renderer.h"
#include "nav/sim/visible_footprint.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

TEST(SimRender, DiveWritesPngFramesAndThumbnails) {
  const auto dir = scratch_dir("render");
  SimOptions o;
  o.out_dir = dir.string();
  o.mission.images = 3;
  o.render_images = true;
  simulate_dive(o, sim_config_path().string());
  int images = 0;
  for (const daemon::DiveLogEvent& e : read_log(dir)) {
    const auto* m = std::get_if<navlcm::image_metadata_t>(&e);
    if (!m) continue;
    char expected[32];
    std::snprintf(expected, sizeof expected, "images/%06lld.png",
                  static_cast<long long>(m->frame_id));
    EXPECT_EQ(m->file_path, expected);
    const cv::Mat im = cv::imread((dir / m->file_path).string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(im.empty()) << m->file_path;
    EXPECT_EQ(im.type(), CV_16UC1);
    EXPECT_EQ(im.cols, m->width);
    EXPECT_EQ(im.rows, m->height);
    double lo = 0, hi = 0;
    cv::minMaxLoc(im, &lo, &hi);
    EXPECT_LE(hi, 4095.0) << "12 significant bits";
    cv::Scalar mean, sd;
    cv::meanStdDev(im, mean, sd);
    EXPECT_GT(mean[0], 200.0);
    EXPECT_GT(sd[0], 50.0) << "texture and lighting, not a flat frame";
    EXPECT_EQ(m->thumbnail_width, 160);
    EXPECT_EQ(m->thumbnail_height, 128);
    EXPECT_EQ(m->thumbnail_num_bytes, 160 * 128);
    ++images;
  }
  EXPECT_EQ(images, 3);
}

/// A camera of focal length f looking straight down (no mount), principal point centred.
CameraGeometry pinhole(double f_px, int width_px, int height_px) {
  CameraGeometry cam;
  cam.fx_px = cam.fy_px = f_px;
  cam.cx_px = 0.5 * width_px;
  cam.cy_px = 0.5 * height_px;
  return cam;
}

TEST(SimRender, RendererIsDeterministicAndStrobeLit) {
  const Seafloor floor({-20.0, 20.0, -20.0, 20.0}, 0.0, 200.0, {}, 1);  // wreck far away
  const CameraGeometry cam = pinhole(100.0, 160, 128);
  RenderOptions ro;
  ro.strobe_in_camera_m = core::Vec3::Zero();  // on the optical centre: symmetric light
  const Renderer a(cam, floor, ro, 7), b(cam, floor, ro, 7), c(cam, floor, ro, 8);
  core::Vec12 x = core::Vec12::Zero();
  x[2] = floor.depth_m(0.0, 0.0) - 3.0;
  const cv::Mat ia = a.render(x, 1), ib = b.render(x, 1), ic = c.render(x, 1);
  EXPECT_EQ(cv::norm(ia, ib, cv::NORM_L1), 0.0);
  EXPECT_GT(cv::norm(ia, ic, cv::NORM_L1), 0.0);
  const double centre = cv::mean(ia(cv::Rect(60, 44, 40, 40)))[0];
  const double corner = cv::mean(ia(cv::Rect(0, 0, 30, 30)))[0];
  EXPECT_GT(centre, 1.5 * corner);
  EXPECT_NEAR(centre, ro.target_counts, 0.5 * ro.target_counts) << "auto exposure";
}

TEST(SimRender, RaysMeetTheHullWallsWhereAFineMarchDoes) {
  // Independent reference: march each ray in 1 cm steps until it is below the height field. A
  // camera beside the hull at deck level, looking at its wall and over the deck edge: every
  // pixel must show the first surface point on its ray (an image of one 3-D scene).
  const Seafloor floor({-20.0, 20.0, -25.0, 25.0}, 0.0, 0.0, {}, 1);
  const Renderer renderer(CameraGeometry{}, floor, RenderOptions{}, 1);
  const double mud_m = floor.depth_m(0.0, 18.0), deck_m = floor.depth_m(0.0, 0.0);
  ASSERT_GT(mud_m - deck_m, 8.0) << "the hull stands ~10 m proud";
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> slope(-0.8, 0.8);
  int walls = 0, grazing = 0;
  for (const double y_cam : {15.5, 13.0}) {  // beside the wall over the berm, above the deck
    const core::Vec3 p(0.0, y_cam, deck_m - 1.0);
    for (int k = 0; k < 300; ++k) {
      const core::Vec3 d(slope(rng), slope(rng) - 0.5, 1.0);
      const core::Vec3 q = renderer.surface_point(p, d);
      const core::Vec3 step = 0.01 * d.normalized();
      core::Vec3 r = p;
      while (r.z() < floor.depth_m(r.x(), r.y())) r += step;
      // A ray grazing a corner may cross it within one half-cell step unseen (1 of 600 here).
      if ((q - r).norm() > 0.03) ++grazing;
      EXPECT_NEAR(q.z(), floor.depth_m(q.x(), q.y()), 0.01) << "on the surface";
      if (q.z() - deck_m > 1.0 && mud_m - q.z() > 1.0) ++walls;
    }
  }
  EXPECT_GT(walls, 20) << "rays that meet the wall itself";
  EXPECT_LE(grazing, 6) << "of 600 rays farther than 3 cm from the fine march's hit";
}

TEST(SimRender, TextureIsFilteredByThePixelFootprint) {
  const Seafloor floor({-20.0, 20.0, -20.0, 20.0}, 0.0, 200.0, {}, 1);
  const Renderer r(CameraGeometry{}, floor, RenderOptions{}, 3);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> at(-10.0, 10.0);
  const auto stats = [&](double footprint_m) {
    double sum = 0.0, sum2 = 0.0;
    constexpr int kN = 4000;
    for (int k = 0; k < kN; ++k) {
      const double a = r.albedo(at(rng), at(rng), 0.0, footprint_m);
      sum += a;
      sum2 += a * a;
    }
    return std::pair{sum / kN, sum2 / kN - (sum / kN) * (sum / kN)};
  };
  const auto [mean_point, var_point] = stats(0.0);
  const auto [mean_cm, var_cm] = stats(0.02);    // the 2 cm grain fades out
  const auto [mean_far, var_far] = stats(10.0);  // every octave is below the pixel
  EXPECT_LT(var_cm, var_point);
  EXPECT_GT(var_cm, 0.5 * var_point);  // the coarser octaves stay
  EXPECT_NEAR(mean_cm, mean_point, 0.01);
  EXPECT_NEAR(mean_far, 0.35, 1e-12);  // the octaves' mean, no relief
  EXPECT_LT(var_far, 1e-12);
}

TEST(SimRender, WallsAreTexturedInTheirOwnPlaneAndFloorsKeepThePlanarTexture) {
  const Seafloor floor({-20.0, 20.0, -20.0, 20.0}, 0.0, 200.0, {}, 1);
  const Renderer r(CameraGeometry{}, floor, RenderOptions{}, 3);
  const core::Vec3 up(0.0, 0.0, -1.0), wall_normal(1.0, 0.0, 0.0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> at(-10.0, 10.0);
  double wall_sum = 0.0, wall_sum2 = 0.0, floor_sum = 0.0, floor_sum2 = 0.0;
  constexpr int kN = 2000;
  for (int k = 0; k < kN; ++k) {
    const core::Vec3 q(at(rng), at(rng), 200.0 + at(rng));
    EXPECT_EQ(r.albedo(q, up, 0.0, 0.0), r.albedo(q.x(), q.y(), 0.0, 0.0)) << "a level floor";
    // Down a wall (normal along x) the planar texture would be constant: a vertical streak.
    const double a = r.albedo(q, wall_normal, 0.0, 0.0);
    const double below = r.albedo(q + core::Vec3(0.0, 0.0, 0.5), wall_normal, 0.0, 0.0);
    wall_sum += a - below;
    wall_sum2 += (a - below) * (a - below);
    const double across = r.albedo(q.x(), q.y(), 0.0, 0.0) - r.albedo(q.x(), q.y() + 0.5, 0.0, 0.0);
    floor_sum += across;
    floor_sum2 += across * across;
  }
  const double wall_var = wall_sum2 / kN - std::pow(wall_sum / kN, 2);
  const double floor_var = floor_sum2 / kN - std::pow(floor_sum / kN, 2);
  // Half a metre down the wall the albedo changes as much as half a metre across the floor.
  EXPECT_GT(wall_var, 0.5 * floor_var);
  EXPECT_LT(wall_var, 2.0 * floor_var);
}

TEST(SimRender, VisibleOverlapOfAFlatFloorIsTheFootprintOverlapWithinRange) {
  const Seafloor floor({-30.0, 30.0, -30.0, 30.0}, 0.0, 300.0, {}, 1);  // no wreck near
  const CameraGeometry cam = pinhole(1000.0, 1280, 1024);  // the survey's camera
  const Renderer renderer(cam, floor, RenderOptions{}, 1);
  for (const double altitude_m : {4.0, 10.0}) {
    core::Vec12 a = core::Vec12::Zero(), b = core::Vec12::Zero();
    a[2] = b[2] = floor.depth_m(0.0, 0.0) - altitude_m;
    b[0] = 0.3 * altitude_m;  // along the image's 0.82 x altitude rows: ~63 % overlap
    const auto fa = visible_footprint(renderer, cam, a.head<6>());
    const auto fb = visible_footprint(renderer, cam, b.head<6>());
    const double visible = visible_overlap(fa, fb, cam);
    const double flat = RegistrationOracle::overlap_fraction(
        image_footprint(cam, a, floor.depth_m(0.0, 0.0)), image_footprint(cam, b, floor.depth_m(0.0, 0.0)));
    SCOPED_TRACE(altitude_m);
    if (altitude_m < VisibleFootprintOptions{}.max_range_m) {
      EXPECT_GT(flat, 0.5);
      EXPECT_NEAR(visible, flat, 0.05);
    } else {
      EXPECT_EQ(visible, 0.0) << "the floor is beyond the camera's range";
    }
  }
}

TEST(SimRender, FootprintIsLitSurfaceAndOverlapIsAFractionOfTheImage) {
  const Seafloor floor({-30.0, 30.0, -30.0, 30.0}, 0.0, 300.0, {}, 1);
  const CameraGeometry cam = pinhole(1000.0, 1280, 1024);
  const Renderer renderer(cam, floor, RenderOptions{}, 1);
  core::Vec6 x = core::Vec6::Zero();
  x[2] = floor.depth_m(0.0, 0.0) - 4.0;  // 4 m above the floor
  VisibleFootprint f = visible_footprint(renderer, cam, x);
  const core::Vec3 below = x.head<3>() + core::Vec3(0.0, 0.0, 4.0);
  const core::Vec3 far = x.head<3>() + core::Vec3(0.0, 0.0, 7.9);  // within 8 m, 1/28 as lit
  VisibleFootprintOptions range_only;
  range_only.min_relative_return = 0.0;
  EXPECT_TRUE(in_footprint(f, below));
  EXPECT_FALSE(in_footprint(f, far)) << "too dark for an exposure metered on the floor at 4 m";
  EXPECT_TRUE(in_footprint(f, far, range_only));
  EXPECT_FALSE(in_footprint(f, x.head<3>() + core::Vec3(0.0, 0.0, 8.1), range_only));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(in_footprint(f, core::Vec3(nan, nan, nan), range_only)) << "a ray that met nothing";

  // Only the top quarter of the rows meets the floor (haze below): that sliver is all of its
  // footprint but a quarter of its image.
  for (int r = f.rows / 4; r < f.rows; ++r)
    for (int c = 0; c < f.cols; ++c) {
      f.points_world[static_cast<std::size_t>(r * f.cols + c)] = core::Vec3(nan, nan, nan);
      f.depth_m[static_cast<std::size_t>(r * f.cols + c)] = nan;
    }
  VisibleFootprintOptions of_footprint;
  of_footprint.of_image = false;
  const double quarter = static_cast<double>(f.rows / 4) / f.rows;
  const double of_its_footprint = seen_fraction(f, f, cam, of_footprint);
  EXPECT_GT(of_its_footprint, 0.9);  // all but the grid's points on the image's border
  EXPECT_NEAR(seen_fraction(f, f, cam), quarter * of_its_footprint, 1e-12);
}

}  // namespace
}  // namespace nav::sim::test
