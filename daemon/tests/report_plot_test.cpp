// Tests of the report's plot helpers (nav/report/plot.h): 1-2-5 ticks and labels, the
// data-to-pixel map, and that ellipses and rectangles land on the pixels the geometry says.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "nav/report/plot.h"

namespace nav::report {
namespace {

TEST(PlotTicks, NiceStepsCoverTheRange) {
  EXPECT_EQ(nice_ticks(0.0, 10.0, 5), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  EXPECT_EQ(nice_ticks(-3.2, 3.2, 6), (std::vector<double>{-3, -2, -1, 0, 1, 2, 3}));
  const auto t = nice_ticks(0.013, 0.101, 4);  // 0.088 / 0.02 = 4.4 intervals: closest to 4
  ASSERT_EQ(t.size(), 5u);
  EXPECT_NEAR(t[0], 0.02, 1e-12);
  EXPECT_NEAR(t[1] - t[0], 0.02, 1e-12);
  EXPECT_EQ(tick_label(0.05, 0.05), "0.05");
  EXPECT_EQ(tick_label(200.0, 50.0), "200");
  EXPECT_EQ(tick_label(-1.5, 0.5), "-1.5");
}

/// Bounding box (canvas pixels) of the pixels near `color` (anti-aliased lines blend with
/// the white background).
cv::Rect box_of(const cv::Mat& img, const cv::Scalar& color) {
  const cv::Vec3b c(static_cast<uchar>(color[0]), static_cast<uchar>(color[1]),
                    static_cast<uchar>(color[2]));
  int x0 = img.cols, y0 = img.rows, x1 = -1, y1 = -1;
  for (int r = 0; r < img.rows; ++r) {
    for (int k = 0; k < img.cols; ++k) {
      const cv::Vec3b p = img.at<cv::Vec3b>(r, k);
      if (std::abs(p[0] - c[0]) + std::abs(p[1] - c[1]) + std::abs(p[2] - c[2]) > 90) continue;
      x0 = std::min(x0, k);
      x1 = std::max(x1, k);
      y0 = std::min(y0, r);
      y1 = std::max(y1, r);
    }
  }
  return x1 < 0 ? cv::Rect() : cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
}

TEST(Plot, EllipseHasTheSemiAxesOfItsCovariance) {
  PlotStyle style;
  style.equal_aspect = true;
  Plot plot(-10.0, 10.0, -10.0, 10.0, style);
  // cov diag(4, 1), 3 sigma: semi-axes 6 (x) and 3 (y) data units.
  plot.ellipse({1.0, -2.0}, cv::Matx22d(4, 0, 0, 1), 3.0, colors::kMagenta, 1);
  const cv::Mat img = plot.image();
  const cv::Rect box = box_of(img, colors::kMagenta);
  const double px_per_unit = plot.to_px({1, 0}).x - plot.to_px({0, 0}).x;
  EXPECT_NEAR(box.width, 12.0 * px_per_unit, 3.0);
  EXPECT_NEAR(box.height, 6.0 * px_per_unit, 3.0);
  const cv::Point2d c = plot.to_px({1.0, -2.0});
  EXPECT_NEAR(box.x + 0.5 * box.width, c.x, 2.0);
  EXPECT_NEAR(box.y + 0.5 * box.height, c.y, 2.0);
  EXPECT_GT(plot.to_px({0, -2}).y, plot.to_px({0, 2}).y);  // y up
}

TEST(Plot, FilledRectangleCoversItsDataCornersWithYDown) {
  PlotStyle style;
  style.y_down = true;
  Plot plot(0.0, 100.0, 0.0, 100.0, style);
  plot.fill_rect({10, 20}, {30, 25}, colors::kGreen);
  const cv::Rect box = box_of(plot.image(), colors::kGreen);
  const cv::Point2d a = plot.to_px({10, 20}), b = plot.to_px({30, 25});
  EXPECT_NEAR(box.x, a.x, 1.0);
  EXPECT_NEAR(box.br().x, b.x, 1.0);
  EXPECT_NEAR(box.y, a.y, 1.0);  // y down: row 20 above row 25
  EXPECT_NEAR(box.br().y, b.y, 1.0);
}

TEST(Plot, NonSpdEllipseAndOffCanvasDataAreSafe) {
  Plot plot(0.0, 1.0, 0.0, 1.0, PlotStyle{});
  plot.ellipse({0.5, 0.5}, cv::Matx22d(1, 2, 2, 1), 3.0, colors::kRed, 1);  // indefinite: skipped
  plot.polyline({{-1e300, 0.0}, {1e300, 1.0}}, colors::kBlue, 1);           // clipped, no overflow
  const cv::Mat img = plot.image();
  EXPECT_EQ(box_of(img, colors::kRed).area(), 0);
  EXPECT_EQ(img.cols, 1000);
  EXPECT_EQ(img.rows, 800);
}

}  // namespace
}  // namespace nav::report
