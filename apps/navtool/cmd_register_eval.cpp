// navtool register-eval: registers the rendered frames of a simulated dive (`navtool simulate
// --render-images`) against the truth: every pair of the first --frames frames whose images show
// at least --min-overlap of the same lit surface (nav/sim/visible_footprint.h;
// --min-relative-return: how lit; --overlap-of-footprint: of the smaller lit footprint instead of
// the image; --flat-overlap: of the flat footprints at the depth below each camera), with a prior
// from the truth plus a stated covariance (register_eval.h), multi-threaded over frames and pairs.
// Options: `navtool register-eval --help`; the --json summary's keys: docs/tools.md.
#include <time.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "nav/core/geometry/pose.h"
#include "nav/daemon/config/config.h"
#include "nav/sim/mission.h"
#include "nav/sim/oracle.h"
#include "nav/sim/seafloor.h"
#include "nav/sim/visible_footprint.h"
#include "nav/sim/sensor_streams.h"
#include "nav/vision/draw.h"
#include "nav/vision/two_view_refinement.h"
#include "nav/vision/validation.h"
#include "navtool/commands.h"
#include "navtool/register_eval.h"

namespace nav::tool {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
constexpr double kDeg = 180.0 / std::numbers::pi;

struct EvalArgs {
  std::string dive, draw_path;
  int frames = 320;
  double min_overlap = 0.3;
  bool flat_overlap = false;
  sim::VisibleFootprintOptions visible;
  int threads = 2;
  double draw_scale = 0.5;
  double reliability_delta0 = 0.0;
  vision::ValidationOptions validation = vision::RegistrationOptions{}.validation;
  double max_sigma_deg = validation.max_sigma_rad * kDeg;
  double model_sigma_deg = vision::RegistrationOptions{}.refinement.model_sigma_rad * kDeg;
  double pixel_sigma_px = vision::RegistrationOptions{}.refinement.pixel_sigma_px;
  double band_floor_sigma_px = vision::RegistrationOptions{}.pccs.band_floor_sigma_px;
  double residual_sigma_factor = vision::RegistrationOptions{}.refinement.residual_sigma_factor;
  double systematic_fraction = vision::RegistrationOptions{}.refinement.systematic_noise_fraction;
  bool fixed_kink = false;
  int fig4_every = 1;
  bool json = false;
  bool verbose = false;
  PairEvalOptions pair;
};

struct Frame {
  std::int64_t id = 0;
  vision::Vec6 x_world_camera = vision::Vec6::Zero();
  double floor_depth_m = 0.0;
  sim::Polygon2 footprint;         ///< flat: on the plane at the depth below the camera
  sim::VisibleFootprint visible;   ///< cast onto the 3-D scene (not with --flat-overlap)
  fs::path image;
};

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double median(std::vector<double> v) {
  if (v.empty()) return -1.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// Runs f(k) for k in [0, n) on `threads` threads.
template <class F>
void parallel_for(int n, int threads, F&& f) {
  std::atomic<int> next{0};
  std::vector<std::thread> pool;
  for (int t = 0; t < std::max(1, threads); ++t) {
    pool.emplace_back([&] {
      for (int k = next++; k < n; k = next++) f(k);
    });
  }
  for (auto& t : pool) t.join();
}

struct Dive {
  sim::CameraGeometry geometry;
  vision::CameraIntrinsics camera;
  int bits_per_pixel = 12;
  std::vector<Frame> frames;
};

/// The dive's seafloor, rebuilt from sim.json's options as navtool simulate built it
/// (nav::sim::simulate_dive: plan_mission, Seafloor seeded with derive_seed(seed, 1)).
std::unique_ptr<sim::Seafloor> rebuild_seafloor(const fs::path& dir) {
  std::ifstream in(dir / "sim.json");
  if (!in) throw CommandError("register-eval: cannot read " + (dir / "sim.json").string());
  try {
    const json o = json::parse(in).at("options");
    sim::MissionOptions m;
    m.images = o.at("images").get<int>();
    m.image_period_s = o.at("image_period_s").get<double>();
    m.speed_mps = o.at("speed_mps").get<double>();
    m.line_length_m = o.at("line_length_m").get<double>();
    m.line_spacing_m = o.at("line_spacing_m").get<double>();
    m.altitude_m = o.at("altitude_m").get<double>();
    sim::SeafloorOptions f;
    f.mean_depth_m = o.at("seafloor_depth_m").get<double>();
    f.resolution_m = o.at("seafloor_resolution_m").get<double>();
    const sim::Mission mission = sim::plan_mission(m);
    return std::make_unique<sim::Seafloor>(mission.extent, mission.wreck_x_m, mission.wreck_y_m, f,
                                           sim::derive_seed(o.at("seed").get<std::uint64_t>(), 1));
  } catch (const json::exception& e) {
    throw CommandError("register-eval: " + (dir / "sim.json").string() + ": " + e.what());
  }
}

Dive read_dive(const EvalArgs& args) {
  const fs::path dir(args.dive);
  Dive dive;
  daemon::NavdConfig config;
  try {
    config = daemon::load_config_file((dir / "config.yaml").string());
  } catch (const std::exception& e) {
    throw CommandError("register-eval: " + std::string(e.what()));
  }
  const daemon::SensorConfig* cam = nullptr;
  for (const auto& s : config.sensors)
    if (daemon::is_camera(s.type)) cam = &s;
  if (cam == nullptr) throw CommandError("register-eval: " + dir.string() + "/config.yaml has no camera");
  dive.geometry = sim::CameraGeometry::from_config(*cam);
  dive.camera.fx_px = cam->camera.fx_px;
  dive.camera.fy_px = cam->camera.fy_px;
  dive.camera.cx_px = cam->camera.cx_px;
  dive.camera.cy_px = cam->camera.cy_px;
  dive.camera.width_px = dive.geometry.width_px();
  dive.camera.height_px = dive.geometry.height_px();
  dive.bits_per_pixel = cam->camera.pixel_format == daemon::PixelFormat::kMono16   ? 16
                        : cam->camera.pixel_format == daemon::PixelFormat::kMono12 ? 12
                                                                                   : 8;
  const std::unique_ptr<sim::Seafloor> seafloor = rebuild_seafloor(dir);
  const sim::Renderer renderer(dive.geometry, *seafloor, {}, 0);  // its ray casting only
  std::ifstream csv(dir / "images.csv");
  if (!csv) throw CommandError("register-eval: cannot read " + (dir / "images.csv").string());
  std::string line;
  std::getline(csv, line);  // header
  while (std::getline(csv, line) && static_cast<int>(dive.frames.size()) < args.frames) {
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(ss, cell, ',')) v.push_back(std::stod(cell));
    if (v.size() < 9) throw CommandError("register-eval: images.csv: short row: " + line);
    Frame f;
    f.id = static_cast<std::int64_t>(v[0]);
    core::Vec12 x = core::Vec12::Zero();
    for (int k = 0; k < 6; ++k) x[k] = v[2 + static_cast<std::size_t>(k)];
    f.x_world_camera = core::head_to_tail(x.head<6>(), dive.geometry.x_body_camera);
    f.floor_depth_m = seafloor->depth_m(f.x_world_camera[0], f.x_world_camera[1]);
    if (std::abs(x[2] + v[8] - seafloor->depth_m(x[0], x[1])) > 0.01)
      throw CommandError("register-eval: the seafloor rebuilt from sim.json does not match the "
                         "altitude of frame " + std::to_string(f.id) + " in images.csv");
    f.footprint = sim::image_footprint(dive.geometry, x, f.floor_depth_m);
    if (!args.flat_overlap)
      f.visible = sim::visible_footprint(renderer, dive.geometry, f.x_world_camera);
    char name[32];
    std::snprintf(name, sizeof name, "images/%06lld.png", static_cast<long long>(f.id));
    f.image = dir / name;
    if (!fs::exists(f.image)) throw CommandError("register-eval: missing " + f.image.string());
    dive.frames.push_back(std::move(f));
  }
  if (dive.frames.size() < 2) throw CommandError("register-eval: fewer than 2 rendered frames");
  return dive;
}

cv::Mat read_frame(const Frame& f) {
  cv::Mat m = cv::imread(f.image.string(), cv::IMREAD_UNCHANGED);
  if (m.empty()) throw CommandError("register-eval: cannot read " + f.image.string());
  return m;
}

std::vector<PairTruth> overlapping_pairs(const Dive& dive, double min_overlap, bool flat,
                                        const sim::VisibleFootprintOptions& visible) {
  std::vector<PairTruth> pairs;
  for (std::size_t j = 1; j < dive.frames.size(); ++j) {
    for (std::size_t i = 0; i < j; ++i) {
      const Frame &a = dive.frames[i], &b = dive.frames[j];
      const double overlap =
          flat ? (a.footprint.empty() || b.footprint.empty()
                      ? 0.0
                      : sim::RegistrationOracle::overlap_fraction(a.footprint, b.footprint))
               : sim::visible_overlap(a.visible, b.visible, dive.geometry, visible);
      if (overlap < min_overlap) continue;
      PairTruth t;
      t.i = static_cast<int>(i);
      t.j = static_cast<int>(j);
      t.x_i_j = core::tail_to_tail(a.x_world_camera, b.x_world_camera);
      t.scene_depth_m = a.floor_depth_m - a.x_world_camera[2];
      t.scene_depth_j_m = b.floor_depth_m - b.x_world_camera[2];
      t.overlap = overlap;
      pairs.push_back(t);
    }
  }
  return pairs;
}

json summarise(const EvalArgs& args, const Dive& dive, const std::vector<PairTruth>& pairs,
               const std::vector<PairEval>& evals, const std::vector<double>& features_cpu_ms,
               const std::vector<double>& pair_cpu_ms) {
  const double wrong_chi2 = vision::chi2_5_quantile(0.999);
  std::vector<double> rot, base, nees, wall;
  std::map<std::string, int> failures;
  int wrong = 0;
  long long truths = 0, missed[3] = {0, 0, 0}, pairs_missed[3] = {0, 0, 0};
  for (const PairEval& e : evals) {
    wall.push_back(e.ms);
    truths += e.true_correspondences;
    for (int c = 0; c < 3; ++c) {
      missed[c] += e.missed[c];
      pairs_missed[c] += e.missed[c] > 0 ? 1 : 0;
    }
    if (!e.result.success) {
      ++failures[vision::failure_name(e.result.failure)];
      continue;
    }
    rot.push_back(e.rotation_error_deg);
    base.push_back(e.baseline_error_deg);
    nees.push_back(e.nees);
    if (e.nees > wrong_chi2) ++wrong;
  }
  double nees_sum = 0.0;
  for (double v : nees) nees_sum += v;
  const auto n_ok = static_cast<double>(nees.size());
  return json{
      {"dive", args.dive},
      {"frames", dive.frames.size()},
      {"min_overlap", args.min_overlap},
      {"overlap", args.flat_overlap ? "flat" : "visible"},
      {"min_relative_return", args.visible.min_relative_return},
      {"overlap_of", args.visible.of_image ? "image" : "footprint"},
      {"pairs", pairs.size()},
      {"successes", nees.size()},
      {"success_fraction", pairs.empty() ? 0.0 : n_ok / static_cast<double>(pairs.size())},
      {"median_rotation_error_deg", median(rot)},
      {"median_baseline_direction_error_deg", median(base)},
      {"nees_mean", nees.empty() ? -1.0 : nees_sum / n_ok},
      {"nees_median", median(nees)},
      {"wrong_nees_threshold", wrong_chi2},
      {"wrong", wrong},
      {"wrong_fraction", nees.empty() ? 0.0 : wrong / n_ok},
      {"failures", failures},
      {"prior",
       {{"position_sigma_m", args.pair.prior_position_sigma_m},
        {"angle_sigma_deg", args.pair.prior_angle_sigma_rad * kDeg},
        {"band_floor_sigma_px", args.band_floor_sigma_px},
        {"depth_sigma_fixed_m", args.pair.depth_sigma_fixed_m},
        {"depth_sigma_fraction", args.pair.depth_sigma_fraction}}},
      {"fig4",
       {{"true_correspondences", truths},
        {"missed_exact", missed[0]},
        {"missed_bound", missed[1]},
        {"missed_overconfident", missed[2]},
        {"pairs_missed_exact", pairs_missed[0]},
        {"pairs_missed_bound", pairs_missed[1]},
        {"pairs_missed_overconfident", pairs_missed[2]},
        {"pairs_counted", (evals.size() + static_cast<std::size_t>(args.fig4_every) - 1) /
                              static_cast<std::size_t>(args.fig4_every)},
        {"bound_inflation", args.pair.bound_inflation},
        {"overconfidence", args.pair.overconfidence}}},
      {"timing",
       {{"features_cpu_ms_median", median(features_cpu_ms)},
        {"pair_cpu_ms_median", median(pair_cpu_ms)},
        {"pair_wall_ms_median", median(wall)}}},
  };
}

/// Fig. 4 picture of the successful pair with the most true correspondences.
void draw_pair(const EvalArgs& args, const Dive& dive, const vision::Registration& registration,
               const std::vector<vision::ImageFeatures>& features,
               const std::vector<PairTruth>& pairs, const std::vector<PairEval>& evals) {
  int best = -1;
  for (std::size_t k = 0; k < evals.size(); ++k) {
    if (!evals[k].result.success) continue;
    if (best < 0 || evals[k].true_correspondences > evals[static_cast<std::size_t>(best)].true_correspondences)
      best = static_cast<int>(k);
  }
  if (best < 0) throw CommandError("register-eval: --draw: no pair registered");
  const PairTruth& t = pairs[static_cast<std::size_t>(best)];
  vision::RegistrationDiagnostics d;
  const auto& fi = features[static_cast<std::size_t>(t.i)];
  const auto& fj = features[static_cast<std::size_t>(t.j)];
  evaluate_pair(registration, fi, fj, t, args.pair, &d);
  const vision::RelativePosePrior prior = make_prior(t, args.pair);
  cv::Mat grey_i, grey_j;
  if (!registration.try_preprocess(read_frame(dive.frames[static_cast<std::size_t>(t.i)]), &grey_i).ok() ||
      !registration.try_preprocess(read_frame(dive.frames[static_cast<std::size_t>(t.j)]), &grey_j).ok())
    throw CommandError("register-eval: --draw: preprocessing failed");
  const vision::DrawOptions draw;
  const auto bands = vision::search_bands(fi, d, dive.camera, &prior, registration.options().pccs,
                                          draw.max_epipolar_lines);
  cv::Mat picture = vision::draw_registration(grey_i, grey_j, fi, fj, d, dive.camera, bands, draw);
  if (args.draw_scale > 0.0 && args.draw_scale != 1.0)
    cv::resize(picture, picture, cv::Size(), args.draw_scale, args.draw_scale, cv::INTER_AREA);
  if (!cv::imwrite(args.draw_path, picture))
    throw CommandError("register-eval: cannot write " + args.draw_path);
  std::fprintf(stderr, "register-eval: drew frames %lld-%lld to %s\n",
               static_cast<long long>(dive.frames[static_cast<std::size_t>(t.i)].id),
               static_cast<long long>(dive.frames[static_cast<std::size_t>(t.j)].id),
               args.draw_path.c_str());
}

void run_register_eval(const EvalArgs& args) {
  const Dive dive = read_dive(args);
  vision::RegistrationOptions options;
  options.preprocess.bits_per_pixel = dive.bits_per_pixel;
  options.refinement.reliability_delta0 = args.reliability_delta0;
  options.validation = args.validation;
  options.validation.max_sigma_rad = args.max_sigma_deg / kDeg;
  options.refinement.model_sigma_rad = args.model_sigma_deg / kDeg;
  vision::set_pixel_sigma_keeping_parallax_floor(options.refinement, args.pixel_sigma_px);
  options.refinement.residual_sigma_factor = args.residual_sigma_factor;
  options.refinement.systematic_noise_fraction = args.systematic_fraction;
  options.refinement.kink_at_measured_noise = !args.fixed_kink;
  options.pccs.band_floor_sigma_px = args.band_floor_sigma_px;
  const vision::Registration registration(dive.camera, options);
  const int n = static_cast<int>(dive.frames.size());
  std::vector<vision::ImageFeatures> features(static_cast<std::size_t>(n));
  std::vector<double> features_cpu_ms(static_cast<std::size_t>(n));
  std::vector<std::string> errors(static_cast<std::size_t>(n));
  cv::setNumThreads(1);  // parallel over frames and pairs instead
  parallel_for(n, args.threads, [&](int k) {
    const auto sk = static_cast<std::size_t>(k);
    const cv::Mat raw = cv::imread(dive.frames[sk].image.string(), cv::IMREAD_UNCHANGED);
    const double t0 = thread_cpu_ms();
    const core::Status s = registration.try_features(raw, &features[sk]);
    features_cpu_ms[sk] = thread_cpu_ms() - t0;
    if (!s.ok()) errors[sk] = dive.frames[sk].image.string() + ": " + s.message();
  });
  for (const auto& e : errors)
    if (!e.empty()) throw CommandError("register-eval: " + e);

  const std::vector<PairTruth> pairs =
      overlapping_pairs(dive, args.min_overlap, args.flat_overlap, args.visible);
  std::vector<PairEval> evals(pairs.size());
  std::vector<double> pair_cpu_ms(pairs.size());
  parallel_for(static_cast<int>(pairs.size()), args.threads, [&](int k) {
    const auto sk = static_cast<std::size_t>(k);
    const PairTruth& t = pairs[sk];
    PairEvalOptions options = args.pair;
    options.fig4 = k % args.fig4_every == 0;
    const double t0 = thread_cpu_ms();
    evals[sk] = evaluate_pair(registration, features[static_cast<std::size_t>(t.i)],
                              features[static_cast<std::size_t>(t.j)], t, options);
    pair_cpu_ms[sk] = thread_cpu_ms() - t0;
  });
  if (args.verbose) {
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const PairEval& e = evals[k];
      std::fprintf(stderr,
                   "pair %lld-%lld (overlap %.2f): %s inliers %d/%d true %d (%.2f px) rotation %.3f deg baseline %.2f deg NEES %.1f "
                   "rms %.2f px [from truth rms %.3f rot %.3f] sigma %.2f px area %.3f lev %.3f truths %d missed %d/%d/%d %s\n",
                   static_cast<long long>(dive.frames[static_cast<std::size_t>(pairs[k].i)].id),
                   static_cast<long long>(dive.frames[static_cast<std::size_t>(pairs[k].j)].id),
                   pairs[k].overlap, e.result.success ? "ok" : "FAILED", e.result.inliers, e.result.putative_matches, e.inliers_true, e.inliers_true_rms_px,
                   e.rotation_error_deg, e.baseline_error_deg, e.nees, e.result.reprojection_rms_px, e.truth_start_rms_px, e.truth_start_rotation_deg, e.residual_sigma_px, e.inlier_area_fraction, e.max_leverage,
                   e.true_correspondences, e.missed[0], e.missed[1], e.missed[2], e.result.reason.c_str());
    }
  }
  const json summary = summarise(args, dive, pairs, evals, features_cpu_ms, pair_cpu_ms);
  if (!args.draw_path.empty()) draw_pair(args, dive, registration, features, pairs, evals);
  if (args.json) std::printf("%s\n", summary.dump(2).c_str());
  std::fprintf(stderr,
               "register-eval: %d frames, %zu pairs, %d registered (%.1f %%), median rotation error "
               "%.3f deg, baseline %.2f deg, NEES mean %.2f, wrong %d; Fig. 4 misses %lld / %lld / "
               "%lld of %lld\n",
               n, pairs.size(), summary["successes"].get<int>(),
               100.0 * summary["success_fraction"].get<double>(),
               summary["median_rotation_error_deg"].get<double>(),
               summary["median_baseline_direction_error_deg"].get<double>(),
               summary["nees_mean"].get<double>(), summary["wrong"].get<int>(),
               summary["fig4"]["missed_exact"].get<long long>(),
               summary["fig4"]["missed_bound"].get<long long>(),
               summary["fig4"]["missed_overconfident"].get<long long>(),
               summary["fig4"]["true_correspondences"].get<long long>());
}

void add_register_eval(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* cmd = app.add_subcommand(
      "register-eval",
      "Register the rendered frames of a simulated dive (navtool simulate --render-images) "
      "against the truth: success, rotation and baseline errors, NEES, and the Fig. 4 count of "
      "true correspondences outside the PCCS band for exact, bound and over-confident priors.");
  cmd->add_option("dive", args->dive, "dive directory")->required();
  cmd->add_option("--frames", args->frames, "first frames used (default 320)")
      ->check(CLI::Range(2, 1000000));
  cmd->add_option("--min-overlap", args->min_overlap,
                  "smallest true footprint overlap of a pair (default 0.3)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_flag("--flat-overlap", args->flat_overlap,
                "overlap of the flat footprints at the depth below each camera instead of the "
                "surface both frames see (nav/sim/visible_footprint.h)");
  cmd->add_option("--min-relative-return", args->visible.min_relative_return,
                  "surface lit less than this fraction of a frame's metered return is not in its "
                  "visible footprint (nav/sim/visible_footprint.h; default 1/15, 0: the 8 m range "
                  "alone)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_flag("--overlap-of-footprint", [args](std::int64_t) { args->visible.of_image = false; },
                "visible overlap as a fraction of the smaller lit footprint instead of the image "
                "(nav/sim/visible_footprint.h)");
  cmd->add_option("--threads", args->threads, "worker threads (default 2)")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--prior-sigma-m", args->pair.prior_position_sigma_m,
                  "prior position sigma, each axis (default 0.25 m)");
  cmd->add_option_function<double>(
         "--prior-angle-sigma-deg",
         [args](double deg) { args->pair.prior_angle_sigma_rad = deg / kDeg; },
         "prior roll, pitch and heading sigma, each (default 0.5 deg)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--band-floor-px", args->band_floor_sigma_px,
                  "floor of the PCCS band, sigma px (pccs.h; default: registration.h)")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--seed", args->pair.seed, "seed of the prior draws (default 1)");
  cmd->add_option("--reliability", args->reliability_delta0,
                  "add to each covariance the shift of undetectable blunders of this "
                  "non-centrality (two_view_refinement.h; 4.13: Baarda's; default 0: off)")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--max-leverage", args->validation.max_leverage,
                  "refuse registrations with an inlier of a larger leverage (validation.h; "
                  "default: registration.h)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--min-inliers", args->validation.min_inliers,
                  "refuse registrations with fewer inliers (default: registration.h)")
      ->check(CLI::Range(5, 100000));
  cmd->add_option("--max-sigma-deg", args->max_sigma_deg,
                  "refuse registrations with an angle of a larger sigma and few inliers, deg "
                  "(default: registration.h)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--uncertain-min-inliers", args->validation.uncertain_min_inliers,
                  "inliers a registration needs when an angle's sigma is above --max-sigma-deg "
                  "(default: registration.h)")
      ->check(CLI::Range(5, 100000));
  cmd->add_option("--model-sigma-deg", args->model_sigma_deg,
                  "model error added to every covariance, deg per angle (default: "
                  "registration.h)")
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_option("--systematic-noise-fraction", args->systematic_fraction,
                  "systematic displacement field, fraction of the measured noise (registration.h)")
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_option("--pixel-sigma-px", args->pixel_sigma_px,
                  "feature noise of the two-view refinement, px, and the floor of its "
                  "a-posteriori scaling (default: registration.h)")
      ->check(CLI::Range(0.01, 10.0));
  cmd->add_option("--residual-sigma-factor", args->residual_sigma_factor,
                  "multiplier of the fit's a-posteriori pixel sigma in the covariance's "
                  "scaling (two_view_refinement.h; default: registration.h)")
      ->check(CLI::Range(0.1, 10.0));
  cmd->add_flag("--fixed-kink", args->fixed_kink,
                "reject the refinement's outliers at a kink of 3 pixel sigmas instead of 3 "
                "sigmas of the noise measured on the pair where that is larger "
                "(two_view_refinement.h kink_at_measured_noise)");
  cmd->add_option("--fig4-every", args->fig4_every,
                  "count the Fig. 4 band misses on every k-th pair only (default 1: all)")
      ->check(CLI::Range(1, 1000000));
  cmd->add_option("--draw", args->draw_path, "write the Fig. 4 picture of one pair");
  cmd->add_option("--draw-scale", args->draw_scale, "picture scale (default 0.5)")
      ->check(CLI::Range(0.05, 1.0));
  cmd->add_flag("--json", args->json, "print the summary as JSON on stdout");
  cmd->add_flag("--verbose", args->verbose, "one line per pair on stderr");
  cmd->callback([args] { run_register_eval(*args); });
}

const CommandRegistration kRegister{"register-eval", add_register_eval};

}  // namespace
}  // namespace nav::tool
