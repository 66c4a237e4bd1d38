// Radiometric preprocessing on real frames (illumination flatness and local contrast before
// and after) and its rejection of bad input.
#include "nav/vision/preprocess.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "nav/testing/data.h"
#include "test_cameras.h"

namespace nav::vision {
namespace {

/// A strobe-like falloff: 1 at (0.3 w, 0.4 h), falling as a Gaussian to ~0.2 at the far corner.
cv::Mat falloff(cv::Size size) {
  cv::Mat f(size, CV_32F);
  for (int r = 0; r < size.height; ++r) {
    for (int c = 0; c < size.width; ++c) {
      const double dx = (c - 0.3 * size.width) / size.width;
      const double dy = (r - 0.4 * size.height) / size.width;
      f.at<float>(r, c) = static_cast<float>(std::exp(-(dx * dx + dy * dy) / 0.35));
    }
  }
  return f;
}

/// Real frame as a 12-bit strobe-lit frame: grey x falloff, scaled to 0..4095 in CV_16U.
cv::Mat as_12bit_strobe_frame(const cv::Mat& bgr) {
  cv::Mat grey, f;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  grey.convertTo(f, CV_32F, 1.0 / 255.0);
  f = f.mul(falloff(f.size()));
  cv::Mat out;
  f.convertTo(out, CV_16U, 4095.0);
  return out;
}

std::vector<cv::Mat> sparus_frames(const std::filesystem::path& first, int count) {
  std::vector<cv::Mat> frames;
  for (int k = 1; k <= count; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%02d.png", k);
    frames.push_back(cv::imread((first.parent_path() / name).string(), cv::IMREAD_UNCHANGED));
  }
  return frames;
}

TEST(Preprocess, RealFrameBecomesFlatterAndMoreContrasted) {
  NAV_REQUIRE_DATA(path, "images/sparus/frame_01.png");
  const cv::Mat raw = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(raw.empty());
  cv::Mat out;
  const Preprocessor pre(test::sparus_camera(), PreprocessOptions{});
  ASSERT_TRUE(pre.run(raw, &out).ok());
  EXPECT_EQ(out.type(), CV_8UC1);
  EXPECT_EQ(out.size(), raw.size());
  cv::Mat grey;
  cv::cvtColor(raw, grey, cv::COLOR_BGR2GRAY);
  const double flat_before = illumination_flatness(grey, 4),
               flat_after = illumination_flatness(out, 4);
  const double contrast_before = mean_local_contrast(grey),
               contrast_after = mean_local_contrast(out);
  std::printf("Sparus frame_01: flatness %.3f -> %.3f, local contrast %.3f -> %.3f\n", flat_before,
              flat_after, contrast_before, contrast_after);
  EXPECT_LT(flat_after, 0.6 * flat_before);
  EXPECT_GT(contrast_after, 1.4 * contrast_before);
}

// Colour files come as BGR, or BGRA when they carry alpha (a PNG exported with transparency, a
// grey-plus-alpha PNG): the same grey, the same detector input, the alpha ignored. Also 16 bits
// per channel.
TEST(Preprocess, ColourFramesWithOrWithoutAlphaGiveTheSameGrey) {
  NAV_REQUIRE_DATA(path, "images/sparus/frame_01.png");
  const cv::Mat bgr = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(bgr.channels(), 3);
  cv::Mat bgra, grey, bgr16;
  cv::cvtColor(bgr, bgra, cv::COLOR_BGR2BGRA);
  bgra.forEach<cv::Vec4b>(
      [](cv::Vec4b& p, const int*) { p[3] = static_cast<std::uint8_t>(p[0] / 2); });
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  bgr.convertTo(bgr16, CV_16UC3, 257.0);  // 8 to 16 bits, full scale to full scale

  EXPECT_EQ(cv::norm(to_grey(bgra), grey, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(to_grey(bgr), grey, cv::NORM_INF), 0.0);
  EXPECT_NEAR(illumination_flatness(bgra), illumination_flatness(grey), 1e-12);
  EXPECT_NEAR(mean_local_contrast(bgr), mean_local_contrast(grey), 1e-12);

  const Preprocessor pre(test::sparus_camera(), PreprocessOptions{});
  PreprocessOptions sixteen;
  sixteen.bits_per_pixel = 16;
  const Preprocessor pre16(test::sparus_camera(), sixteen);
  cv::Mat from_grey, from_bgra, from_bgr16;
  ASSERT_TRUE(pre.run(grey, &from_grey).ok());
  ASSERT_TRUE(pre.run(bgra, &from_bgra).ok());
  ASSERT_TRUE(pre16.run(bgr16, &from_bgr16).ok());
  EXPECT_EQ(cv::norm(from_bgra, from_grey, cv::NORM_INF), 0.0);
  // 16-bit grey rounds differently from 8-bit grey: a grey level at most.
  EXPECT_LE(cv::norm(from_bgr16, from_grey, cv::NORM_L1) / static_cast<double>(grey.total()), 1.0);
}

TEST(Preprocess, TwelveBitStrobeFalloffIsRemovedByLowPassAndByRunningMean) {
  NAV_REQUIRE_DATA(path, "images/sparus/frame_01.png");
  const std::vector<cv::Mat> frames = sparus_frames(path, 22);
  std::vector<cv::Mat> frames12;
  for (const cv::Mat& f : frames) frames12.push_back(as_12bit_strobe_frame(f));
  IlluminationMean mean;
  for (const cv::Mat& f : frames12) ASSERT_TRUE(mean.add(f, 12).ok());
  EXPECT_EQ(mean.frames(), 22u);

  PreprocessOptions options;
  options.undistort = false;
  cv::Mat unit8;
  frames12[5].convertTo(unit8, CV_8U, 255.0 / 4095.0);
  const double raw_flatness = illumination_flatness(unit8, 4);
  for (auto mode : {IlluminationCompensation::kLowPass, IlluminationCompensation::kRunningMean}) {
    options.illumination = mode;
    const Preprocessor pre(test::sparus_camera(), options);
    cv::Mat out;
    const core::Status s = pre.run(frames12[5], &out, &mean);
    ASSERT_TRUE(s.ok()) << s.message();
    const double flat = illumination_flatness(out, 4);
    std::printf("12-bit strobe frame, mode %d: flatness %.3f -> %.3f\n", static_cast<int>(mode),
                raw_flatness, flat);
    EXPECT_LT(flat, 0.3 * raw_flatness);
  }
  // Without compensation the falloff survives the stretch (CLAHE only evens it partly).
  options.illumination = IlluminationCompensation::kNone;
  options.clahe_clip_limit = 0.0;
  cv::Mat out;
  ASSERT_TRUE(Preprocessor(test::sparus_camera(), options).run(frames12[5], &out).ok());
  EXPECT_GT(illumination_flatness(out, 4), 0.5 * raw_flatness);
}

TEST(Preprocess, BadInputIsRejectedWithAClearMessage) {
  const CameraIntrinsics camera = test::sparus_camera();
  const Preprocessor pre(camera, PreprocessOptions{});
  cv::Mat out;
  auto message = [&](const cv::Mat& raw) {
    const core::Status s = pre.run(raw, &out);
    EXPECT_FALSE(s.ok());
    return s.message();
  };
  EXPECT_NE(message(cv::Mat()).find("empty"), std::string::npos);
  EXPECT_NE(message(cv::Mat(288, 384, CV_32F, cv::Scalar(0.5))).find("neither 8-bit"),
            std::string::npos);
  EXPECT_NE(message(cv::Mat(288, 384, CV_8UC2, cv::Scalar(1))).find("2 channels"),
            std::string::npos);
  EXPECT_NE(message(cv::Mat(100, 100, CV_8U, cv::Scalar(1))).find("calibration is for 384x288"),
            std::string::npos);
  // A 16-bit frame with 16 significant bits handed in as 12-bit data.
  EXPECT_NE(message(cv::Mat(288, 384, CV_16U, cv::Scalar(40000))).find("wrong pixel depth"),
            std::string::npos);

  // Truncated raw buffer.
  std::vector<std::uint8_t> buffer(384 * 288 * 2 - 10);
  cv::Mat frame;
  const core::Status truncated =
      frame_from_buffer(buffer.data(), buffer.size(), 384, 288, 2, &frame);
  EXPECT_FALSE(truncated.ok());
  EXPECT_NE(truncated.message().find("truncated"), std::string::npos) << truncated.message();
  buffer.resize(384 * 288 * 2);
  EXPECT_TRUE(frame_from_buffer(buffer.data(), buffer.size(), 384, 288, 2, &frame).ok());
  EXPECT_EQ(frame.type(), CV_16UC1);

  // Running mean requested without one, and a mean of another size.
  PreprocessOptions running;
  running.illumination = IlluminationCompensation::kRunningMean;
  const Preprocessor pre_running(camera, running);
  const cv::Mat ok_frame(288, 384, CV_16U, cv::Scalar(1000));
  EXPECT_FALSE(pre_running.run(ok_frame, &out).ok());
  IlluminationMean small;
  ASSERT_TRUE(small.add(cv::Mat(10, 10, CV_16U, cv::Scalar(5)), 12).ok());
  EXPECT_FALSE(small.add(ok_frame, 12).ok());
  const core::Status mismatch = pre_running.run(ok_frame, &out, &small);
  EXPECT_FALSE(mismatch.ok());
  EXPECT_NE(mismatch.message().find("illumination mean is 10x10"), std::string::npos);

  // Missing calibration: undistortion needs the intrinsics.
  CameraIntrinsics missing = camera;
  missing.fx_px = 0.0;
  const core::Status no_calibration =
      Preprocessor(missing, PreprocessOptions{}).run(ok_frame, &out);
  EXPECT_FALSE(no_calibration.ok());
  EXPECT_NE(no_calibration.message().find("missing calibration"), std::string::npos);
}

}  // namespace
}  // namespace nav::vision
