#pragma once
// Radiometric preprocessing of strobe-lit underwater frames for the feature detectors.
//
// A strobe-lit seafloor image is dominated by the lighting pattern: strong falloff from the
// strobe's footprint centre, vignetting, and attenuation with range (Singh, Howland & Pizarro,
// "Advances in large-area photomosaicking underwater", IEEE JOE 29(3), 2004; Singh et al.,
// "Towards high-resolution imaging from underwater vehicles", IJRR 26(1), 2007). The pattern
// moves little from frame to frame, so it is estimated either
//   - per frame, as a wide Gaussian low-pass of the frame itself (kLowPass), or
//   - for the dive, as the running mean of the frames (IlluminationMean, owned by the caller),
// and divided out (a flat-field correction). The flat-fielded frame is stretched between robust
// percentiles to 8 bit and contrast-limited adaptive histogram equalisation (CLAHE; Zuiderveld,
// Graphics Gems IV, 1994) evens local contrast for the detectors.
//
// Inputs: CV_8U, or CV_16U with `bits_per_pixel` significant bits (Mono12 in 16-bit containers
// is bits_per_pixel = 12; a value above 2^bits - 1 is reported as a wrong depth), 1, 3 or 4
// channels (BGR and BGRA, as OpenCV reads colour files, are converted to grey; alpha is
// ignored). Undistortion resamples the image to the ideal pinhole
// of the same intrinsics, so feature coordinates measured on the output are ideal pixels.

#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>

#include "nav/core/status.h"
#include "nav/vision/vision_types.h"

namespace nav::vision {

enum class IlluminationCompensation : std::uint8_t {
  kNone = 0,
  kLowPass,      ///< Divide by a Gaussian low-pass of the frame.
  kRunningMean,  ///< Divide by the dive's running mean image (IlluminationMean).
};

struct PreprocessOptions {
  int bits_per_pixel = 12;  ///< Significant bits of CV_16U input (8 < bits <= 16).
  bool undistort = true;    ///< Resample to the ideal pinhole (needs the calibration).
  IlluminationCompensation illumination = IlluminationCompensation::kLowPass;
  double lowpass_sigma_fraction = 0.125;  ///< Low-pass sigma as a fraction of the image width.
  double stretch_low_percentile = 0.5;    ///< Percentile mapped to grey 0 after flat-fielding.
  double stretch_high_percentile = 99.5;  ///< Percentile mapped to grey 255.
  double clahe_clip_limit = 2.0;          ///< CLAHE clip limit (0 disables CLAHE).
  int clahe_tiles = 8;                    ///< CLAHE tiles across the image width.
};

/// Checks a raw frame before preprocessing: not empty, CV_8U or CV_16U, 1, 3 or 4 channels, size
/// equal to the calibration's width x height when that is set, and for CV_16U no value above
/// 2^bits_per_pixel - 1. The message names the frame's actual and the expected property.
core::Status validate_raw_frame(const cv::Mat& raw, const CameraIntrinsics& camera,
                                const PreprocessOptions& options);

/// Wraps a raw camera buffer (row-major, no padding) as a frame; error when the buffer holds
/// fewer bytes than width x height x bytes per pixel (a truncated frame). bytes_per_pixel 1 or 2.
core::Status frame_from_buffer(const std::uint8_t* data, std::size_t size_bytes, int width_px,
                               int height_px, int bytes_per_pixel, cv::Mat* frame);

/// The grey of a 1-, 3- (BGR) or 4-channel (BGRA) image, same depth (the image itself if grey).
cv::Mat to_grey(const cv::Mat& image);

/// Grey frame as CV_32F in [0, 1] (full scale 2^bits - 1 for CV_16U, 255 for CV_8U).
cv::Mat to_unit_float(const cv::Mat& raw, int bits_per_pixel);

/// Running mean image of a dive's frames (unit-float grey, same size), the illumination model of
/// IlluminationCompensation::kRunningMean. Owned by the caller, who adds frames as they arrive;
/// not thread-safe to add while another thread preprocesses with it.
class IlluminationMean {
 public:
  /// Adds one frame (any input accepted by validate_raw_frame); error on a size mismatch.
  core::Status add(const cv::Mat& raw, int bits_per_pixel);
  std::size_t frames() const { return frames_; }
  /// Smoothed mean (a light Gaussian removes the residual scene texture); empty before add().
  cv::Mat mean() const;

 private:
  cv::Mat sum_;  ///< CV_64F sum of the unit-float frames.
  std::size_t frames_ = 0;
};

/// Precomputes the undistortion maps of one camera; immutable afterwards, so a single instance
/// may serve concurrent callers.
class Preprocessor {
 public:
  Preprocessor(const CameraIntrinsics& camera, const PreprocessOptions& options);

  /// 8-bit flat-fielded, contrast-normalised grey image for the detectors. `mean` is required
  /// for IlluminationCompensation::kRunningMean (with at least one frame) and ignored otherwise.
  core::Status run(const cv::Mat& raw, cv::Mat* out_8u,
                   const IlluminationMean* mean = nullptr) const;

  const PreprocessOptions& options() const { return options_; }
  const CameraIntrinsics& camera() const { return camera_; }

 private:
  CameraIntrinsics camera_;
  PreprocessOptions options_;
  cv::Mat map_x_, map_y_;  ///< Undistortion maps (CV_32F), empty when not undistorting.
};

/// Flatness of an image: coefficient of variation (std / mean) of the means of a grid of
/// blocks x blocks tiles. Near 0 for an evenly lit image; large for strobe falloff.
double illumination_flatness(const cv::Mat& image, int blocks = 8);

/// Mean over tiles of the local RMS contrast (tile std / tile mean), on a blocks x blocks grid.
double mean_local_contrast(const cv::Mat& image, int blocks = 8);

}  // namespace nav::vision
