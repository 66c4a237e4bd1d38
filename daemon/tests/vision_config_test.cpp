// The `vision:` section of the navd config (config/vision_config.h, config/README.md "vision").
#include <gtest/gtest.h>

#include <filesystem>

#include "nav/daemon/config/config.h"

namespace nav::daemon {
namespace {

const std::string kSensors = R"(
sensors:
  - name: dvl
    type: dvl_pd0
    transport: {type: serial, device: /dev/ttyUSB0}
)";

TEST(VisionConfig, DefaultsOffAndSectionReadsEveryKey) {
  EXPECT_FALSE(parse_config(kSensors).vision.enabled);
  const NavdConfig c = parse_config(kSensors + R"(
vision:
  enabled: true
  threads: 3
  cache_images: 10
  queue_capacity: 5
  answer_delay_s: 2.5
  image_dir: /data/frames
  image_width_px: 640
  image_height_px: 480
  depth_sigma_fraction: 0.2
  depth_sigma_floor_m: 0.5
  max_leverage: 0.75
  pixel_sigma_px: 0.3
  residual_sigma_factor: 1.9
  model_sigma_deg: 0.05
  systematic_noise_fraction: 0.25
  min_inliers: 25
  max_sigma_deg: 1.5
  uncertain_min_inliers: 80
  band_floor_sigma_px: 25
)");
  const VisionConfig& v = c.vision;
  EXPECT_TRUE(v.enabled);
  EXPECT_EQ(v.threads, 3);
  EXPECT_EQ(v.cache_images, 10);
  EXPECT_EQ(v.queue_capacity, 5);
  EXPECT_EQ(v.answer_delay_s, 2.5);
  EXPECT_EQ(v.image_dir, "/data/frames");
  EXPECT_EQ(v.image_width_px, 640);
  EXPECT_EQ(v.image_height_px, 480);
  EXPECT_EQ(v.depth_sigma_fraction, 0.2);
  EXPECT_EQ(v.depth_sigma_floor_m, 0.5);
  EXPECT_EQ(v.max_leverage, 0.75);
  EXPECT_EQ(v.pixel_sigma_px, 0.3);
  EXPECT_EQ(v.residual_sigma_factor, 1.9);
  EXPECT_EQ(v.model_sigma_deg, 0.05);
  EXPECT_EQ(v.systematic_noise_fraction, 0.25);
  EXPECT_EQ(v.min_inliers, 25);
  EXPECT_EQ(v.max_sigma_deg, 1.5);
  EXPECT_EQ(v.uncertain_min_inliers, 80);
  EXPECT_EQ(v.band_floor_sigma_px, 25.0);
  const VisionConfig defaults = parse_config(kSensors).vision;
  EXPECT_FALSE(defaults.max_leverage.has_value());
  // The loop's noise model, not the registration pipeline's (vision_config.h).
  EXPECT_EQ(defaults.pixel_sigma_px, 0.5);
  EXPECT_EQ(defaults.residual_sigma_factor, 1.0);
  EXPECT_EQ(defaults.model_sigma_deg, 0.2);
  EXPECT_EQ(defaults.systematic_noise_fraction, 1.0);
  EXPECT_FALSE(defaults.min_inliers.has_value());
  EXPECT_FALSE(defaults.max_sigma_deg.has_value());
  EXPECT_FALSE(defaults.uncertain_min_inliers.has_value());
  EXPECT_FALSE(defaults.band_floor_sigma_px.has_value());
}

TEST(VisionConfig, OutOfRangeAndUnknownKeysNameTheKey) {
  try {
    parse_config(kSensors + "vision: {threads: 0}\n", "t.yaml");
    FAIL() << "threads 0 accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("vision.threads"), std::string::npos) << e.what();
  }
  try {
    parse_config(kSensors + "vision: {max_leverage: 1.5}\n", "t.yaml");
    FAIL() << "leverage 1.5 accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("vision.max_leverage"), std::string::npos) << e.what();
  }
  try {
    parse_config(kSensors + "vision: {min_inliers: 2}\n", "t.yaml");
    FAIL() << "min_inliers 2 accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("vision.min_inliers"), std::string::npos) << e.what();
  }
  try {
    parse_config(kSensors + "vision: {band_floor_sigma_px: -1}\n", "t.yaml");
    FAIL() << "a negative band floor accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("vision.band_floor_sigma_px"), std::string::npos)
        << e.what();
  }
  try {
    parse_config(kSensors + "vision: {thread: 2}\n", "t.yaml");
    FAIL() << "unknown key accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("thread"), std::string::npos) << e.what();
  }
}

TEST(VisionConfig, SimYamlHasTheRenderedFrameSizeAndVisionOff) {
  const NavdConfig c =
      load_config_file((std::filesystem::path(NAV_SOURCE_DIR) / "config" / "sim.yaml").string());
  EXPECT_FALSE(c.vision.enabled);
  EXPECT_EQ(c.vision.image_width_px, 1280);
  EXPECT_EQ(c.vision.image_height_px, 1024);
}

}  // namespace
}  // namespace nav::daemon
