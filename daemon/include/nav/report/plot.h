#pragma once
// A small 2-D plot drawn with OpenCV imgproc (the report figures, paper Figs. 1, 2, 3, 5): a
// white canvas with a framed plot area, "nice" (1-2-5) ticks with labels, axis labels, title
// and a legend. Data are given in data coordinates and clipped to the plot area.
// Use: construct with the data limits, draw, then image() (axes/legend are drawn last).

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace nav::report {

struct PlotStyle {
  int width_px = 1000;
  int height_px = 800;
  bool equal_aspect = false;  ///< same metres per pixel on both axes (maps)
  bool y_down = false;        ///< y grows downwards (matrix rows, Fig. 2)
};

/// BGR colours used by every figure, so legends agree across figures.
namespace colors {
inline const cv::Scalar kBlack{0, 0, 0};
inline const cv::Scalar kGrey{150, 150, 150};
inline const cv::Scalar kRed{40, 40, 220};
inline const cv::Scalar kBlue{200, 90, 20};
inline const cv::Scalar kGreen{40, 150, 40};
inline const cv::Scalar kOrange{0, 140, 255};
inline const cv::Scalar kMagenta{180, 40, 180};
}  // namespace colors

class Plot {
 public:
  /// Data limits [x_min, x_max] x [y_min, y_max] (widened by 3 % on each side, and to equal
  /// scale when style.equal_aspect). Degenerate ranges are widened to +-0.5.
  Plot(double x_min, double x_max, double y_min, double y_max, const PlotStyle& style);

  void set_title(const std::string& title) { title_ = title; }
  void set_subtitle(const std::string& subtitle) { subtitle_ = subtitle; }
  void set_labels(const std::string& x_label, const std::string& y_label);

  /// A polyline through the points (data coordinates).
  void polyline(const std::vector<cv::Point2d>& points, const cv::Scalar& color, int thickness = 1);
  void segment(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& color,
               int thickness = 1);
  /// Filled circles of radius_px at the points.
  void markers(const std::vector<cv::Point2d>& points, const cv::Scalar& color, int radius_px);
  /// Filled axis-aligned rectangle between two data corners (at least one pixel).
  void fill_rect(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& color);
  /// Outline rectangle between two data corners.
  void rect(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& color, int thickness = 1);
  /// Dashed vertical line at x across the plot area.
  void vline_dashed(double x, const cv::Scalar& color, int thickness = 2);
  /// The ellipse {c + scale * L u : |u| = 1} of the 2x2 covariance cov = L L^T (scale = number
  /// of sigmas times any inflation), as a 72-segment polyline. Non-SPD covariances are skipped.
  void ellipse(const cv::Point2d& center, const cv::Matx22d& cov, double scale,
               const cv::Scalar& color, int thickness = 1);
  /// Free text at a data position (top-left anchored), black.
  void text(const cv::Point2d& at, const std::string& s, double font_scale = 0.45);

  /// One legend entry: a line sample (or a filled box when `box`) and the label.
  void add_legend(const std::string& label, const cv::Scalar& color, bool box = false);
  /// A line of text at the bottom of the legend (e.g. "ellipses inflated x20").
  void add_note(const std::string& note) { notes_.push_back(note); }

  /// The finished figure: data, then frame, ticks, labels, title, legend (CV_8UC3).
  cv::Mat image() const;

  /// Pixel position of a data point (canvas coordinates).
  cv::Point2d to_px(const cv::Point2d& p) const;

 private:
  struct LegendEntry {
    std::string label;
    cv::Scalar color;
    bool box;
  };
  void draw_axes(cv::Mat& canvas) const;
  void draw_legend(cv::Mat& canvas) const;
  cv::Point px_in_area(const cv::Point2d& p) const;

  PlotStyle style_;
  cv::Rect area_;  ///< plot area in canvas pixels
  double x_min_, x_max_, y_min_, y_max_;
  cv::Mat canvas_;
  std::string title_, subtitle_, x_label_, y_label_;
  std::vector<LegendEntry> legend_;
  std::vector<std::string> notes_;
};

/// Tick positions in [lo, hi] with the 1-2-5 step giving the interval count closest to `target`.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);
/// A tick label: as few decimals as the tick step needs ("-1.5", "200", "0.02").
std::string tick_label(double value, double step);

/// Writes a PNG (cv::imwrite); throws ReportError naming the path on failure.
void write_png(const std::string& path, const cv::Mat& image);

}  // namespace nav::report
