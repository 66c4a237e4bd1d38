// navtool demo: runs the exactly sparse delayed-state filter (Eustice et al., RSS 2005) on the
// built-in simulated lawnmower camera survey (core/sim/survey.h) and prints a summary: images,
// states, camera links, final robot position error against the truth with its 3-sigma, NEES
// of the final robot pose, information-matrix size and fill, and mean time per predict,
// update and mean recovery (steady clock here: core has no clocks).
// --json: one JSON object on stdout; otherwise a human-readable summary on stderr (commands.h:
// stdout carries machine-readable output only).
#include <nlohmann/json.hpp>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "nav/core/filter/esdf.h"
#include "nav/core/geometry/rotation.h"
#include "nav/core/sim/survey.h"
#include "navtool/commands.h"

namespace nav::tool {
namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

struct DemoArgs {
  int images = 200;
  std::uint64_t seed = 1;
  int relinearise_every = 4;  // once per image with the default 4 steps per image
  bool json = false;
};

/// Accumulates wall time of one kind of operation.
struct Timer {
  double total_us = 0.0;
  long count = 0;
  double mean_us() const { return count > 0 ? total_us / static_cast<double>(count) : 0.0; }
};

template <class Fn>
core::Status timed(Timer& t, Fn&& fn) {
  const auto t0 = Clock::now();
  core::Status s = fn();
  t.total_us += std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
  ++t.count;
  return s;
}

void require(const core::Status& s, const char* what) {
  if (!s.ok()) throw CommandError(std::string("demo: ") + what + ": " + s.to_string());
}

/// Robot block covariance (12 x 12) from one sparse Cholesky of Λ.
core::Mat12 robot_covariance(const core::Esdf& filter) {
  const Eigen::SparseMatrix<double> L = filter.information().to_sparse();
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> chol(L);
  if (chol.info() != Eigen::Success) throw CommandError("demo: information matrix not SPD");
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(L.rows(), 12);
  E.topRows<12>().setIdentity();
  const Eigen::MatrixXd X = chol.solve(E);
  return X.topRows<12>();
}

void run_demo(const DemoArgs& args) {
  core::sim::SurveyOptions opt;
  opt.num_images = args.images;
  opt.seed = args.seed;
  const core::sim::Survey sv = core::sim::simulate_survey(opt);

  core::Esdf filter(12);
  require(filter.initialize(sv.x0_mean, sv.P0), "initialize");
  std::vector<int> image_blocks;
  Timer predict_t, update_t, recover_t;
  const auto start = Clock::now();
  for (size_t k = 0; k < sv.steps.size(); ++k) {
    const core::sim::SurveyStep& st = sv.steps[k];
    core::Mat12 F, Q;
    const core::Vec12 f =
        core::sim::predicted_mean(sv, st, filter.mean_block(core::Esdf::kRobotBlock), &F, &Q);
    int kept = -1;
    require(timed(predict_t, [&] { return filter.predict(f, F, Q, st.image >= 0, &kept); }),
            "predict");
    if (st.image >= 0) image_blocks.push_back(kept);
    const int r = core::Esdf::kRobotBlock;
    require(timed(update_t, [&] { return filter.update(sv.dvl, r, st.dvl, sv.R_dvl); }), "DVL");
    require(timed(update_t,
                  [&] { return filter.update(sv.heading, r, st.heading, sv.R_heading); }),
            "heading");
    require(timed(update_t,
                  [&] { return filter.update(sv.attitude, r, st.attitude, sv.R_attitude); }),
            "attitude");
    require(timed(update_t, [&] { return filter.update(sv.depth, r, st.depth, sv.R_depth); }),
            "depth");
    for (const core::sim::CameraLink& l : st.links) {
      const int a = image_blocks[static_cast<size_t>(l.image_a)];
      const int b = image_blocks[static_cast<size_t>(l.image_b)];
      require(timed(update_t, [&] { return filter.update(sv.camera, a, b, l.z, sv.R_camera); }),
              "camera link");
    }
    if ((k + 1) % static_cast<size_t>(args.relinearise_every) == 0 || k + 1 == sv.steps.size()) {
      require(timed(recover_t, [&] { return filter.recover_mean_direct(); }), "mean recovery");
    }
  }
  const double total_s = std::chrono::duration<double>(Clock::now() - start).count();

  const core::Vec12 x_true = sv.steps.back().x_true;
  const core::Vec12 x_est = filter.mean_block(core::Esdf::kRobotBlock);
  const core::Mat12 P = robot_covariance(filter);
  core::Vec6 e = x_true.head<6>() - x_est.head<6>();
  for (int i = 3; i < 6; ++i) e[i] = core::wrap_angle(e[i]);
  const double nees = e.dot(P.topLeftCorner<6, 6>().ldlt().solve(e));
  const double pos_err = e.head<3>().norm();
  const double pos_sigma = std::sqrt(P.topLeftCorner<3, 3>().trace());
  const core::InformationMatrix& L = filter.information();
  const double dim = static_cast<double>(L.dim());
  const double nnz = static_cast<double>(L.to_sparse().nonZeros());

  json out;
  out["images"] = image_blocks.size();
  out["steps"] = sv.steps.size();
  out["states"] = filter.num_blocks();
  out["camera_links"] = sv.num_links;
  out["cross_track_links"] = sv.num_cross_track_links;
  out["seed"] = args.seed;
  out["final_position_error_m"] = pos_err;
  out["final_position_sigma_m"] = pos_sigma;
  out["final_position_3sigma_m"] = 3.0 * pos_sigma;
  out["final_position_error_xyz_m"] = {e[0], e[1], e[2]};
  out["final_position_sigma_xyz_m"] = {std::sqrt(P(0, 0)), std::sqrt(P(1, 1)),
                                       std::sqrt(P(2, 2))};
  out["final_pose_nees"] = nees;
  out["final_pose_nees_dof"] = 6;
  out["info_matrix_dim"] = L.dim();
  out["info_matrix_block_pairs"] = L.num_off_diagonal_pairs();
  out["info_matrix_nonzeros"] = static_cast<long long>(nnz);
  out["info_matrix_nonzero_fraction"] = nnz / (dim * dim);
  out["mean_predict_us"] = predict_t.mean_us();
  out["mean_update_us"] = update_t.mean_us();
  out["mean_recovery_us"] = recover_t.mean_us();
  out["predicts"] = predict_t.count;
  out["updates"] = update_t.count;
  out["recoveries"] = recover_t.count;
  out["total_s"] = total_s;

  if (args.json) {
    std::cout << out.dump() << std::endl;
    return;
  }
  std::fprintf(stderr,
               "navtool demo: ESDF on a simulated lawnmower survey (seed %llu)\n"
               "  images %zu, steps %zu, states %d, camera links %zu (%zu cross-track)\n"
               "  final robot position error %.3f m (3-sigma %.3f m), pose NEES %.2f (6 dof)\n"
               "  information matrix %lld x %lld, %zu block pairs, non-zeros %.3f %%\n"
               "  mean time: predict %.1f us, update %.1f us, direct mean recovery %.1f us\n"
               "  total %.2f s\n",
               static_cast<unsigned long long>(args.seed), image_blocks.size(), sv.steps.size(),
               filter.num_blocks(), sv.num_links, sv.num_cross_track_links, pos_err,
               3.0 * pos_sigma, nees, static_cast<long long>(L.dim()),
               static_cast<long long>(L.dim()), L.num_off_diagonal_pairs(),
               100.0 * nnz / (dim * dim), predict_t.mean_us(), update_t.mean_us(),
               recover_t.mean_us(), total_s);
}

void add_demo(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  CLI::App* cmd = app.add_subcommand(
      "demo",
      "Run the ESDF (RSS 2005) on the built-in simulated lawnmower camera survey (DVL, heading, "
      "attitude, depth at Table II precision; camera links incl. loop closures) and print a "
      "summary: error vs truth, NEES, information-matrix fill, timings.");
  cmd->add_option("--images", args->images, "images in the survey (default 200)")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--seed", args->seed, "random seed of the simulation (default 1)");
  cmd->add_option("--relinearise-every", args->relinearise_every,
                  "steps between direct mean recoveries (default 4: once per image)")
      ->check(CLI::Range(1, 1000000));
  cmd->add_flag("--json", args->json, "one JSON object on stdout (else a summary on stderr)");
  cmd->callback([args] { run_demo(*args); });
}

const CommandRegistration kRegister{"demo", add_demo};

}  // namespace
}  // namespace nav::tool
