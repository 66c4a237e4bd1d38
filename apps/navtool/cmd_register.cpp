// navtool register: two-view registration of one image pair with nav_vision (the registration
// stage of Eustice et al., RSS 2005, section III-C), for inspecting a pair offline.
//   navtool register IMG_I IMG_J --camera CAMERA.yaml [--prior PRIOR.json] [--json]
//                    [--draw OUT.png]
// CAMERA.yaml: a `camera:` block with config/sim.yaml's camera keys: fx, fy, cx, cy,
// distortion [k1, k2, p1, p2, k3], optional pixel_format (mono8 | mono12 | mono16, the bits of
// 16-bit images; without it a 16-bit file is taken at its 16-bit full scale), width, height.
// PRIOR.json: {"x_i_j": [x, y, z, roll, pitch, heading] of camera j in camera i (m, rad),
//              "covariance": 36 numbers row-major, "scene_depth_m": d, "scene_depth_sigma_m": s}.
// --json prints one object: success, reason, measurement (5), covariance (25 row-major),
// inliers, putative_matches, descriptor_comparisons, ms {features_i, features_j, matching,
// essential, refinement, validation, total}. Unreadable input: message, exit status 1; a pair
// that does not register is not an error (success false, exit status 0).
#include <yaml-cpp/yaml.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "nav/vision/camera_model.h"
#include "nav/vision/draw.h"
#include "nav/vision/registration.h"
#include "navtool/commands.h"

namespace nav::tool {
namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

struct RegisterArgs {
  std::string image_i, image_j, camera_path, prior_path, draw_path;
  bool json = false;
};

double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

struct CameraFile {
  vision::CameraIntrinsics camera;
  int bits_per_pixel = 16;  ///< of 16-bit files (a file carries no pixel format)
};

CameraFile read_camera(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw CommandError("register: cannot read camera file " + path + ": " + e.what());
  }
  const YAML::Node c = root["camera"];
  if (!c || !c.IsMap()) throw CommandError("register: " + path + " has no `camera:` block");
  CameraFile out;
  auto number = [&](const char* key, bool required, double fallback) {
    if (!c[key]) {
      if (required) throw CommandError("register: " + path + ": camera." + key + " is missing");
      return fallback;
    }
    try {
      return c[key].as<double>();
    } catch (const YAML::Exception&) {
      throw CommandError("register: " + path + ": camera." + key + " is not a number");
    }
  };
  out.camera.fx_px = number("fx", true, 0.0);
  out.camera.fy_px = number("fy", true, 0.0);
  out.camera.cx_px = number("cx", true, 0.0);
  out.camera.cy_px = number("cy", true, 0.0);
  out.camera.width_px = static_cast<int>(number("width", false, 0.0));
  out.camera.height_px = static_cast<int>(number("height", false, 0.0));
  if (const YAML::Node d = c["distortion"]) {
    if (!d.IsSequence() || d.size() != 5) {
      throw CommandError("register: " + path + ": camera.distortion must be [k1, k2, p1, p2, k3]");
    }
    out.camera.k1 = d[0].as<double>();
    out.camera.k2 = d[1].as<double>();
    out.camera.p1 = d[2].as<double>();
    out.camera.p2 = d[3].as<double>();
    out.camera.k3 = d[4].as<double>();
  }
  if (const YAML::Node f = c["pixel_format"]) {
    const std::string format = f.as<std::string>();
    if (format == "mono8") {
      out.bits_per_pixel = 8;
    } else if (format == "mono12") {
      out.bits_per_pixel = 12;
    } else if (format == "mono16") {
      out.bits_per_pixel = 16;
    } else {
      throw CommandError("register: " + path + ": camera.pixel_format '" + format +
                         "' is not mono8, mono12 or mono16");
    }
  }
  if (const core::Status s = vision::validate(out.camera); !s.ok()) {
    throw CommandError("register: " + path + ": " + s.message());
  }
  return out;
}

vision::RelativePosePrior read_prior(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw CommandError("register: cannot open prior file " + path);
  json j;
  try {
    in >> j;
  } catch (const json::exception& e) {
    throw CommandError("register: " + path + " is not JSON: " + e.what());
  }
  vision::RelativePosePrior prior;
  try {
    const auto x = j.at("x_i_j").get<std::vector<double>>();
    if (x.size() != 6) throw CommandError("register: " + path + ": x_i_j needs 6 numbers");
    const auto p = j.at("covariance").get<std::vector<double>>();
    if (p.size() != 36) throw CommandError("register: " + path + ": covariance needs 36 numbers");
    for (int r = 0; r < 6; ++r) {
      prior.x_i_j[r] = x[static_cast<std::size_t>(r)];
      for (int c = 0; c < 6; ++c) prior.covariance(r, c) = p[static_cast<std::size_t>(6 * r + c)];
    }
    prior.scene_depth_m = j.at("scene_depth_m").get<double>();
    prior.scene_depth_sigma_m = j.at("scene_depth_sigma_m").get<double>();
  } catch (const json::exception& e) {
    throw CommandError("register: " + path + ": " + e.what());
  }
  return prior;
}

cv::Mat read_image(const std::string& path) {
  cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    throw CommandError("register: cannot read image " + path + " (missing, truncated or not an image)");
  }
  return image;
}

void run_register(const RegisterArgs& args) {
  const CameraFile camera_file = read_camera(args.camera_path);
  std::unique_ptr<vision::RelativePosePrior> prior;
  if (!args.prior_path.empty()) {
    prior = std::make_unique<vision::RelativePosePrior>(read_prior(args.prior_path));
  }
  const cv::Mat image_i = read_image(args.image_i), image_j = read_image(args.image_j);
  vision::RegistrationOptions options;
  options.preprocess.bits_per_pixel = camera_file.bits_per_pixel;
  const vision::Registration registration(camera_file.camera, options);

  vision::ImageFeatures features_i, features_j;
  auto t = Clock::now();
  if (const core::Status s = registration.try_features(image_i, &features_i); !s.ok()) {
    throw CommandError("register: " + args.image_i + ": " + s.message());
  }
  const double features_i_ms = ms_since(t);
  t = Clock::now();
  if (const core::Status s = registration.try_features(image_j, &features_j); !s.ok()) {
    throw CommandError("register: " + args.image_j + ": " + s.message());
  }
  const double features_j_ms = ms_since(t);

  vision::RegistrationDiagnostics diagnostics;
  const vision::RegistrationResult r =
      registration.register_pair(features_i, features_j, prior.get(), &diagnostics);

  if (!args.draw_path.empty()) {
    cv::Mat grey_i, grey_j;
    (void)registration.try_preprocess(image_i, &grey_i);
    (void)registration.try_preprocess(image_j, &grey_j);
    const cv::Mat picture =
        vision::draw_registration(grey_i, grey_j, features_i, features_j, diagnostics,
                                  camera_file.camera,
                                  vision::search_bands(features_i, diagnostics, camera_file.camera,
                                                       prior.get(), options.pccs,
                                                       vision::DrawOptions{}.max_epipolar_lines));
    if (!cv::imwrite(args.draw_path, picture)) {
      throw CommandError("register: cannot write " + args.draw_path);
    }
  }

  const auto& tm = diagnostics.timings;
  if (args.json) {
    json out;
    out["success"] = r.success;
    out["reason"] = r.reason;
    out["measurement"] = std::vector<double>(r.z.data(), r.z.data() + 5);
    std::vector<double> cov(25);
    for (int a = 0; a < 5; ++a)
      for (int b = 0; b < 5; ++b) cov[static_cast<std::size_t>(5 * a + b)] = r.covariance(a, b);
    out["covariance"] = cov;
    out["inliers"] = r.inliers;
    out["putative_matches"] = r.putative_matches;
    out["descriptor_comparisons"] = r.descriptor_comparisons;
    out["features"] = {features_i.size(), features_j.size()};
    out["reprojection_rms_px"] = r.reprojection_rms_px;
    out["noise_sigma_px"] = r.noise_sigma_px;
    out["prior_chi2"] = r.prior_chi2;
    out["ms"] = {{"features_i", features_i_ms}, {"features_j", features_j_ms},
                 {"matching", tm.matching_ms},  {"essential", tm.essential_ms},
                 {"refinement", tm.refinement_ms}, {"validation", tm.validation_ms},
                 {"total", tm.total_ms + features_i_ms + features_j_ms}};
    std::printf("%s\n", out.dump().c_str());
  } else {
    std::fprintf(stderr,
                 "register %s -> %s: %s%s\n  features %zu / %zu, putative %d (%zu comparisons), "
                 "inliers %d\n  z = [%.4f %.4f %.4f %.4f %.4f] rad\n  %.1f ms features, %.1f ms "
                 "pair\n",
                 args.image_i.c_str(), args.image_j.c_str(), r.success ? "registered" : "FAILED: ",
                 r.success ? "" : r.reason.c_str(), features_i.size(), features_j.size(),
                 r.putative_matches, r.descriptor_comparisons, r.inliers, r.z[0], r.z[1], r.z[2],
                 r.z[3], r.z[4], features_i_ms + features_j_ms, tm.total_ms);
  }
}

void add_register(CLI::App& app) {
  auto args = std::make_shared<RegisterArgs>();
  CLI::App* cmd = app.add_subcommand(
      "register",
      "Register an image pair (two-view relative pose, 5-DOF measurement with covariance) as "
      "navd's camera stage does: preprocessing, Harris + SIFT features, pose-constrained (with "
      "--prior) or unconstrained matching, LMedS essential matrix, refinement, validation.");
  cmd->add_option("image_i", args->image_i, "first image (8-bit or 12/16-bit PNG/TIFF)")->required();
  cmd->add_option("image_j", args->image_j, "second image")->required();
  cmd->add_option("--camera", args->camera_path, "YAML file with a `camera:` block")->required();
  cmd->add_option("--prior", args->prior_path, "JSON relative-pose prior of camera j in camera i");
  cmd->add_option("--draw", args->draw_path, "write the Fig. 4 picture (epipolar lines, search bands)");
  cmd->add_flag("--json", args->json, "print one JSON object on stdout");
  cmd->callback([args] { run_register(*args); });
}

const CommandRegistration kRegister{"register", add_register};

}  // namespace
}  // namespace nav::tool
