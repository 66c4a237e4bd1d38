#include "nav/vision/preprocess.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "nav/vision/camera_model.h"

namespace nav::vision {

using core::Status;
using core::StatusCode;

namespace {

Status invalid(const std::string& message) {
  return Status::Error(StatusCode::kInvalidArgument, "preprocess: " + message);
}

std::string size_string(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

/// Value of the given percentile (0..100) of a CV_32F image, from every `stride`-th pixel.
float percentile(const cv::Mat& image_32f, double pct, int stride) {
  std::vector<float> v;
  v.reserve(image_32f.total() / static_cast<std::size_t>(stride) + 1);
  for (int r = 0; r < image_32f.rows; r += stride) {
    const float* row = image_32f.ptr<float>(r);
    for (int c = (r / stride) % stride; c < image_32f.cols; c += stride) v.push_back(row[c]);
  }
  if (v.empty()) return 0.0f;
  const auto k = static_cast<std::size_t>(std::clamp(pct / 100.0, 0.0, 1.0) * (v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

cv::Mat gaussian_lowpass(const cv::Mat& image_32f, double sigma_px) {
  // A wide Gaussian on a 4x decimated copy, upsampled back: same low-pass to within the
  // bilinear interpolation error at a 16th of the cost.
  cv::Mat small, blurred, full_size;
  cv::resize(image_32f, small, cv::Size(), 0.25, 0.25, cv::INTER_AREA);
  cv::GaussianBlur(small, blurred, cv::Size(), std::max(0.5, sigma_px / 4.0), 0.0,
                   cv::BORDER_REFLECT);
  cv::resize(blurred, full_size, image_32f.size(), 0.0, 0.0, cv::INTER_LINEAR);
  return full_size;
}

}  // namespace

Status validate_raw_frame(const cv::Mat& raw, const CameraIntrinsics& camera,
                          const PreprocessOptions& options) {
  if (raw.empty()) return invalid("empty frame (unreadable or truncated image file?)");
  if (raw.depth() != CV_8U && raw.depth() != CV_16U) {
    return invalid("frame depth " + std::to_string(raw.depth()) +
                   " is neither 8-bit (CV_8U) nor 16-bit (CV_16U)");
  }
  if (raw.channels() != 1 && raw.channels() != 3 && raw.channels() != 4) {
    return invalid("frame has " + std::to_string(raw.channels()) +
                   " channels, expected 1 (grey), 3 (BGR) or 4 (BGRA)");
  }
  if (camera.width_px > 0 && camera.height_px > 0 &&
      (raw.cols != camera.width_px || raw.rows != camera.height_px)) {
    return invalid("frame is " + size_string(raw.cols, raw.rows) + " but the calibration is for " +
                   size_string(camera.width_px, camera.height_px));
  }
  if (raw.depth() == CV_16U) {
    if (options.bits_per_pixel <= 8 || options.bits_per_pixel > 16) {
      return invalid("bits_per_pixel " + std::to_string(options.bits_per_pixel) +
                     " outside (8, 16] for a 16-bit frame");
    }
    double max_value = 0.0;
    cv::minMaxLoc(raw.reshape(1), nullptr, &max_value);
    const double full_scale = std::ldexp(1.0, options.bits_per_pixel) - 1.0;
    if (max_value > full_scale) {
      return invalid("16-bit frame has value " + std::to_string(static_cast<int>(max_value)) +
                     " above the " + std::to_string(options.bits_per_pixel) +
                     "-bit full scale " + std::to_string(static_cast<int>(full_scale)) +
                     " (wrong pixel depth?)");
    }
  }
  return Status::Ok();
}

Status frame_from_buffer(const std::uint8_t* data, std::size_t size_bytes, int width_px,
                         int height_px, int bytes_per_pixel, cv::Mat* frame) {
  if (width_px <= 0 || height_px <= 0) return invalid("frame size " + size_string(width_px, height_px));
  if (bytes_per_pixel != 1 && bytes_per_pixel != 2) {
    return invalid("bytes_per_pixel " + std::to_string(bytes_per_pixel) + ", expected 1 or 2");
  }
  const std::size_t need = static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px) *
                           static_cast<std::size_t>(bytes_per_pixel);
  if (data == nullptr || size_bytes < need) {
    return invalid("truncated frame: " + std::to_string(size_bytes) + " bytes, a " +
                   size_string(width_px, height_px) + " frame of " +
                   std::to_string(bytes_per_pixel) + " byte(s) per pixel needs " +
                   std::to_string(need));
  }
  const int type = bytes_per_pixel == 1 ? CV_8UC1 : CV_16UC1;
  // Copy: the frame must not alias the caller's transport buffer.
  cv::Mat(height_px, width_px, type, const_cast<std::uint8_t*>(data)).copyTo(*frame);
  return Status::Ok();
}

cv::Mat to_grey(const cv::Mat& image) {
  cv::Mat grey = image;
  if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  if (image.channels() == 4) cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  return grey;
}

cv::Mat to_unit_float(const cv::Mat& raw, int bits_per_pixel) {
  const cv::Mat grey = to_grey(raw);
  const double full_scale =
      raw.depth() == CV_16U ? std::ldexp(1.0, bits_per_pixel) - 1.0 : 255.0;
  cv::Mat out;
  grey.convertTo(out, CV_32F, 1.0 / full_scale);
  return out;
}

Status IlluminationMean::add(const cv::Mat& raw, int bits_per_pixel) {
  PreprocessOptions options;
  options.bits_per_pixel = bits_per_pixel;
  CameraIntrinsics any_size;
  if (Status s = validate_raw_frame(raw, any_size, options); !s.ok()) return s;
  if (!sum_.empty() && raw.size() != sum_.size()) {
    return invalid("illumination mean: frame " + size_string(raw.cols, raw.rows) +
                   " differs from the accumulated " + size_string(sum_.cols, sum_.rows));
  }
  cv::Mat unit = to_unit_float(raw, bits_per_pixel);
  if (sum_.empty()) sum_ = cv::Mat::zeros(raw.size(), CV_64F);
  cv::accumulate(unit, sum_);
  ++frames_;
  return Status::Ok();
}

cv::Mat IlluminationMean::mean() const {
  if (frames_ == 0) return {};
  cv::Mat mean;
  sum_.convertTo(mean, CV_32F, 1.0 / static_cast<double>(frames_));
  // Few frames leave scene texture in the mean; a light low-pass (1/64 of the width) keeps the
  // illumination pattern, which varies on the scale of the whole frame.
  cv::GaussianBlur(mean, mean, cv::Size(), std::max(1.0, mean.cols / 64.0));
  return mean;
}

Preprocessor::Preprocessor(const CameraIntrinsics& camera, const PreprocessOptions& options)
    : camera_(camera), options_(options) {
  if (options_.undistort && has_distortion(camera_) && camera_.width_px > 0 &&
      camera_.height_px > 0 && validate(camera_).ok()) {
    const cv::Matx33d K = camera_matrix(camera_);
    cv::initUndistortRectifyMap(K, distortion_coefficients(camera_), cv::noArray(), K,
                                cv::Size(camera_.width_px, camera_.height_px), CV_32FC1, map_x_,
                                map_y_);
  }
}

Status Preprocessor::run(const cv::Mat& raw, cv::Mat* out_8u, const IlluminationMean* mean) const {
  if (Status s = validate_raw_frame(raw, camera_, options_); !s.ok()) return s;
  if (options_.undistort && has_distortion(camera_)) {
    if (Status s = validate(camera_); !s.ok()) return s;
    if (map_x_.empty()) {
      return invalid("undistortion needs the calibration's image size (width_px, height_px)");
    }
  }
  cv::Mat unit = to_unit_float(raw, options_.bits_per_pixel);

  // Flat field: divide by the illumination estimate (floored at 1% of its mean, so dark corners
  // do not blow up noise).
  cv::Mat illumination;
  switch (options_.illumination) {
    case IlluminationCompensation::kNone:
      break;
    case IlluminationCompensation::kLowPass:
      illumination = gaussian_lowpass(unit, options_.lowpass_sigma_fraction * unit.cols);
      break;
    case IlluminationCompensation::kRunningMean:
      if (mean == nullptr || mean->frames() == 0) {
        return invalid("running-mean illumination compensation needs an IlluminationMean with frames");
      }
      illumination = mean->mean();
      if (illumination.size() != unit.size()) {
        return invalid("illumination mean is " + size_string(illumination.cols, illumination.rows) +
                       ", frame is " + size_string(unit.cols, unit.rows));
      }
      break;
  }
  cv::Mat flat = unit;
  if (!illumination.empty()) {
    const double floor = std::max(1e-6, 0.01 * cv::mean(illumination)[0]);
    cv::max(illumination, floor, illumination);
    cv::divide(unit, illumination, flat);
  }

  // Robust stretch to 8 bit, then CLAHE.
  const float lo = percentile(flat, options_.stretch_low_percentile, 3);
  float hi = percentile(flat, options_.stretch_high_percentile, 3);
  if (!(hi > lo)) hi = lo + 1e-6f;
  cv::Mat grey;
  flat.convertTo(grey, CV_8U, 255.0 / (hi - lo), -255.0 * lo / (hi - lo));
  if (options_.clahe_clip_limit > 0.0) {
    const int tiles_x = std::max(1, options_.clahe_tiles);
    const int tiles_y = std::max(1, static_cast<int>(std::lround(tiles_x * grey.rows /
                                                                 static_cast<double>(grey.cols))));
    // One CLAHE object per call: its apply() keeps scratch buffers, so sharing is not safe.
    cv::Ptr<cv::CLAHE> clahe =
        cv::createCLAHE(options_.clahe_clip_limit, cv::Size(tiles_x, tiles_y));
    clahe->apply(grey, grey);
  }
  if (!map_x_.empty()) {
    cv::remap(grey, *out_8u, map_x_, map_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  } else {
    *out_8u = grey;
  }
  return Status::Ok();
}

double illumination_flatness(const cv::Mat& image, int blocks) {
  cv::Mat f;
  to_grey(image).convertTo(f, CV_64F);
  std::vector<double> means;
  for (int by = 0; by < blocks; ++by) {
    for (int bx = 0; bx < blocks; ++bx) {
      const cv::Rect r(bx * f.cols / blocks, by * f.rows / blocks, f.cols / blocks, f.rows / blocks);
      means.push_back(cv::mean(f(r))[0]);
    }
  }
  double m = 0.0, s2 = 0.0;
  for (double v : means) m += v;
  m /= static_cast<double>(means.size());
  for (double v : means) s2 += (v - m) * (v - m);
  return m > 0.0 ? std::sqrt(s2 / static_cast<double>(means.size())) / m : 0.0;
}

double mean_local_contrast(const cv::Mat& image, int blocks) {
  cv::Mat f;
  to_grey(image).convertTo(f, CV_64F);
  double sum = 0.0;
  for (int by = 0; by < blocks; ++by) {
    for (int bx = 0; bx < blocks; ++bx) {
      const cv::Rect r(bx * f.cols / blocks, by * f.rows / blocks, f.cols / blocks, f.rows / blocks);
      cv::Scalar mean, std;
      cv::meanStdDev(f(r), mean, std);
      sum += mean[0] > 0.0 ? std[0] / mean[0] : 0.0;
    }
  }
  return sum / (blocks * blocks);
}

}  // namespace nav::vision
