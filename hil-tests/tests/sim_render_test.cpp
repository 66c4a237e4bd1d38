// --render-images: 16-bit PNG frames with 12 significant bits beside the log, referenced by
// NAV_IMAGE with an 8-bit thumbnail; the renderer is deterministic, textured, and strobe-lit
// (brighter in the middle than in the corners over a flat floor).
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <random>
#include <variant>

#include "nav/sim/renderer.h"
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

TEST(SimRender, RendererIsDeterministicAndStrobeLit) {
  const Seafloor floor({-20.0, 20.0, -20.0, 20.0}, 0.0, 200.0, {}, 1);  // wreck far away
  CameraGeometry cam;
  cam.fx_px = cam.fy_px = 100.0;
  cam.cx_px = 80.0;
  cam.cy_px = 64.0;
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

}  // namespace
}  // namespace nav::sim::test
