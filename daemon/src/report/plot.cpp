// Plot: see plot.h.
#include "nav/report/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "nav/report/csv_table.h"

namespace nav::report {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kMarginLeft = 95, kMarginRight = 25, kMarginTop = 70, kMarginBottom = 65;

void put_text(cv::Mat& img, const std::string& s, cv::Point at, double scale, int thickness = 1,
              const cv::Scalar& color = colors::kBlack) {
  cv::putText(img, s, at, kFont, scale, color, thickness, cv::LINE_AA);
}

cv::Size text_size(const std::string& s, double scale, int thickness = 1) {
  int baseline = 0;
  return cv::getTextSize(s, kFont, scale, thickness, &baseline);
}

void widen(double& lo, double& hi) {
  if (!(hi > lo)) {
    lo -= 0.5;
    hi += 0.5;
  }
  const double pad = 0.03 * (hi - lo);
  lo -= pad;
  hi += pad;
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int target) {
  const double raw = (hi - lo) / std::max(target, 1);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  // The 1-2-5 step whose interval count is closest to the target.
  double step = mag;
  for (double m : {2.0, 5.0, 10.0}) {
    const double target_d = static_cast<double>(std::max(target, 1));
    if (std::abs((hi - lo) / (m * mag) - target_d) < std::abs((hi - lo) / step - target_d)) {
      step = m * mag;
    }
  }
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step) {
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  }
  return ticks;
}

std::string tick_label(double value, double step) {
  const int decimals = std::clamp(static_cast<int>(-std::floor(std::log10(step) + 1e-9)), 0, 6);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}

Plot::Plot(double x_min, double x_max, double y_min, double y_max, const PlotStyle& style)
    : style_(style), x_min_(x_min), x_max_(x_max), y_min_(y_min), y_max_(y_max) {
  area_ = cv::Rect(kMarginLeft, kMarginTop, style.width_px - kMarginLeft - kMarginRight,
                   style.height_px - kMarginTop - kMarginBottom);
  widen(x_min_, x_max_);
  widen(y_min_, y_max_);
  if (style.equal_aspect) {
    const double sx = (x_max_ - x_min_) / area_.width, sy = (y_max_ - y_min_) / area_.height;
    const double s = std::max(sx, sy);
    const double cx = 0.5 * (x_min_ + x_max_), cy = 0.5 * (y_min_ + y_max_);
    x_min_ = cx - 0.5 * s * area_.width;
    x_max_ = cx + 0.5 * s * area_.width;
    y_min_ = cy - 0.5 * s * area_.height;
    y_max_ = cy + 0.5 * s * area_.height;
  }
  canvas_ = cv::Mat(style.height_px, style.width_px, CV_8UC3, cv::Scalar(255, 255, 255));
}

void Plot::set_labels(const std::string& x_label, const std::string& y_label) {
  x_label_ = x_label;
  y_label_ = y_label;
}

cv::Point2d Plot::to_px(const cv::Point2d& p) const {
  const double fx = (p.x - x_min_) / (x_max_ - x_min_);
  double fy = (p.y - y_min_) / (y_max_ - y_min_);
  if (!style_.y_down) fy = 1.0 - fy;
  return {area_.x + fx * area_.width, area_.y + fy * area_.height};
}

cv::Point Plot::px_in_area(const cv::Point2d& p) const {
  const cv::Point2d c = to_px(p);
  // Clamp far-away points so the integer conversion cannot overflow; clipping does the rest.
  const double lim = 1e6;
  return {static_cast<int>(std::lround(std::clamp(c.x - area_.x, -lim, lim))),
          static_cast<int>(std::lround(std::clamp(c.y - area_.y, -lim, lim)))};
}

void Plot::polyline(const std::vector<cv::Point2d>& points, const cv::Scalar& color,
                    int thickness) {
  if (points.size() < 2) return;
  std::vector<cv::Point> px;
  px.reserve(points.size());
  for (const auto& p : points) px.push_back(px_in_area(p));
  cv::Mat area = canvas_(area_);
  cv::polylines(area, px, false, color, thickness, cv::LINE_AA);
}

void Plot::segment(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& color,
                   int thickness) {
  cv::Mat area = canvas_(area_);
  cv::line(area, px_in_area(a), px_in_area(b), color, thickness, cv::LINE_AA);
}

void Plot::markers(const std::vector<cv::Point2d>& points, const cv::Scalar& color, int radius_px) {
  cv::Mat area = canvas_(area_);
  for (const auto& p : points) cv::circle(area, px_in_area(p), radius_px, color, cv::FILLED);
}

void Plot::fill_rect(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& color) {
  cv::Point pa = px_in_area(a), pb = px_in_area(b);
  cv::Rect r(cv::Point(std::min(pa.x, pb.x), std::min(pa.y, pb.y)),
             cv::Point(std::max(pa.x, pb.x), std::max(pa.y, pb.y)));
  r.width = std::max(r.width, 1);
  r.height = std::max(r.height, 1);
  r &= cv::Rect(0, 0, area_.width, area_.height);
  if (r.area() > 0) canvas_(area_)(r).setTo(color);
}

void Plot::rect(const cv::Point2d& a, const cv::Point2d& b, const cv::Scalar& color,
                int thickness) {
  cv::Mat area = canvas_(area_);
  cv::rectangle(area, px_in_area(a), px_in_area(b), color, thickness, cv::LINE_AA);
}

void Plot::vline_dashed(double x, const cv::Scalar& color, int thickness) {
  cv::Mat area = canvas_(area_);
  const int px = px_in_area({x, y_min_}).x;
  for (int y = 0; y < area_.height; y += 16) {
    cv::line(area, {px, y}, {px, std::min(y + 9, area_.height - 1)}, color, thickness);
  }
}

void Plot::ellipse(const cv::Point2d& center, const cv::Matx22d& cov, double scale,
                   const cv::Scalar& color, int thickness) {
  const double a = cov(0, 0), b = 0.5 * (cov(0, 1) + cov(1, 0)), c = cov(1, 1);
  if (!(a > 0.0) || !(a * c - b * b > 0.0)) return;
  const double l00 = std::sqrt(a), l10 = b / l00, l11 = std::sqrt(c - l10 * l10);
  std::vector<cv::Point2d> pts;
  for (int k = 0; k <= 72; ++k) {
    const double th = 2.0 * M_PI * k / 72.0;
    const double u = std::cos(th), v = std::sin(th);
    pts.emplace_back(center.x + scale * l00 * u, center.y + scale * (l10 * u + l11 * v));
  }
  polyline(pts, color, thickness);
}

void Plot::text(const cv::Point2d& at, const std::string& s, double font_scale) {
  const cv::Point p = px_in_area(at);
  cv::Mat area = canvas_(area_);
  put_text(area, s, {p.x, p.y + text_size(s, font_scale).height}, font_scale);
}

void Plot::add_legend(const std::string& label, const cv::Scalar& color, bool box) {
  legend_.push_back({label, color, box});
}

void Plot::draw_axes(cv::Mat& img) const {
  cv::rectangle(img, area_, colors::kBlack, 1);
  const double tick_scale = 0.45;
  const auto xt = nice_ticks(x_min_, x_max_);
  const double x_step = xt.size() > 1 ? xt[1] - xt[0] : 1.0;
  for (double t : xt) {
    const int px = static_cast<int>(std::lround(to_px({t, y_min_}).x));
    const int y0 = area_.br().y;
    cv::line(img, {px, y0}, {px, y0 + 6}, colors::kBlack, 1);
    const std::string s = tick_label(t, x_step);
    const cv::Size sz = text_size(s, tick_scale);
    put_text(img, s, {px - sz.width / 2, y0 + 10 + sz.height}, tick_scale);
  }
  const auto yt = nice_ticks(y_min_, y_max_);
  const double y_step = yt.size() > 1 ? yt[1] - yt[0] : 1.0;
  for (double t : yt) {
    const int py = static_cast<int>(std::lround(to_px({x_min_, t}).y));
    cv::line(img, {area_.x - 6, py}, {area_.x, py}, colors::kBlack, 1);
    const std::string s = tick_label(t, y_step);
    const cv::Size sz = text_size(s, tick_scale);
    put_text(img, s, {area_.x - 10 - sz.width, py + sz.height / 2}, tick_scale);
  }
  // Axis labels: x centred below the ticks, y rotated 90 degrees left of the tick labels.
  const double label_scale = 0.55;
  if (!x_label_.empty()) {
    const cv::Size sz = text_size(x_label_, label_scale);
    put_text(img, x_label_, {area_.x + (area_.width - sz.width) / 2, style_.height_px - 14},
             label_scale);
  }
  if (!y_label_.empty()) {
    const cv::Size sz = text_size(y_label_, label_scale);
    cv::Mat label(sz.height + 8, sz.width + 4, CV_8UC3, cv::Scalar(255, 255, 255));
    put_text(label, y_label_, {2, sz.height + 2}, label_scale);
    cv::Mat rotated;
    cv::rotate(label, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int top = std::max(0, area_.y + (area_.height - rotated.rows) / 2);
    const int rows = std::min(rotated.rows, img.rows - top);
    rotated.rowRange(0, rows).copyTo(img(cv::Rect(6, top, rotated.cols, rows)));
  }
  if (!title_.empty()) {
    const cv::Size sz = text_size(title_, 0.65, 2);
    put_text(img, title_, {(style_.width_px - sz.width) / 2, 28}, 0.65, 2);
  }
  if (!subtitle_.empty()) {
    const cv::Size sz = text_size(subtitle_, 0.5);
    put_text(img, subtitle_, {(style_.width_px - sz.width) / 2, 54}, 0.5);
  }
}

void Plot::draw_legend(cv::Mat& img) const {
  if (legend_.empty() && notes_.empty()) return;
  const double scale = 0.45;
  const int row_h = 20, sample_w = 28;
  int width = 0;
  for (const auto& e : legend_)
    width = std::max(width, sample_w + 8 + text_size(e.label, scale).width);
  for (const auto& n : notes_) width = std::max(width, text_size(n, scale).width);
  const int rows = static_cast<int>(legend_.size() + notes_.size());
  const cv::Rect box(area_.br().x - width - 24, area_.y + 8, width + 16, rows * row_h + 10);
  img(box).setTo(cv::Scalar(255, 255, 255));
  cv::rectangle(img, box, colors::kGrey, 1);
  int y = box.y + 5;
  for (const auto& e : legend_) {
    const int mid = y + row_h / 2;
    if (e.box) {
      cv::rectangle(img, cv::Rect(box.x + 8, mid - 6, sample_w - 8, 12), e.color, cv::FILLED);
    } else {
      cv::line(img, {box.x + 8, mid}, {box.x + sample_w, mid}, e.color, 2, cv::LINE_AA);
    }
    put_text(img, e.label, {box.x + sample_w + 8, mid + 5}, scale);
    y += row_h;
  }
  for (const auto& n : notes_) {
    put_text(img, n, {box.x + 8, y + row_h / 2 + 5}, scale);
    y += row_h;
  }
}

cv::Mat Plot::image() const {
  cv::Mat img = canvas_.clone();
  draw_axes(img);
  draw_legend(img);
  return img;
}

void write_png(const std::string& path, const cv::Mat& image) {
  bool ok = false;
  try {
    ok = cv::imwrite(path, image);
  } catch (const cv::Exception& e) {
    throw ReportError(path + ": cannot write PNG: " + e.what());
  }
  if (!ok) throw ReportError(path + ": cannot write PNG");
}

}  // namespace nav::report
