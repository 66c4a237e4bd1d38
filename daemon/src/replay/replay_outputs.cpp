// Replay analysis (exact marginals, bound checks, Fig. 3 log-det ratios), the JSON summary and
// the replay output files of hil-tests/README.md.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include <Eigen/CholmodSupport>

#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/core/recovery/markov_blanket.h"
#include "nav/daemon/replay/dive_replay.h"

namespace nav::daemon {
namespace {

constexpr int kD = 12;
constexpr double kConservativeTolerance = 1e-9;  // relative, as the report's check

/// Pose rows/cols [0..5] of r and [d..d+5] of i from a 2d x 2d joint.
core::Mat12 pose_joint(const Eigen::MatrixXd& joint) {
  core::Mat12 p;
  const int idx[12] = {0, 1, 2, 3, 4, 5, kD, kD + 1, kD + 2, kD + 3, kD + 4, kD + 5};
  for (int a = 0; a < 12; ++a) {
    for (int b = 0; b < 12; ++b) p(a, b) = joint(idx[a], idx[b]);
  }
  return p;
}

double logdet_or_nan(const core::Mat6& ours, const core::Mat6& exact) {
  try {
    return core::logdet_ratio(ours, exact);
  } catch (const std::exception&) {
    return std::numeric_limits<double>::quiet_NaN();
  }
}

/// The exact robot column Σ_{*0} = Λ⁻¹ E_0 by one sparse Cholesky solve (12 right-hand sides):
/// with the exact marginals it gives every exact joint (0, i) without a solve per state.
Eigen::MatrixXd exact_robot_column(const core::InformationMatrix& info) {
  const Eigen::SparseMatrix<double> lambda = info.to_sparse();
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> llt(lambda);
  if (llt.info() != Eigen::Success) throw std::runtime_error("Cholesky of the final Λ failed");
  const Eigen::MatrixXd e0 = Eigen::MatrixXd::Identity(lambda.rows(), kD);
  Eigen::MatrixXd column = llt.solve(e0);
  if (llt.info() != Eigen::Success) throw std::runtime_error("robot column solve failed");
  return column;
}

void logdet_rows(NavFilter& slam, const core::ExactMarginals& exact, const core::Vec12& robot,
                 const Eigen::VectorXd& mean, ReplayAnalysis& a) {
  const core::Esdf& esdf = slam.esdf();
  const Eigen::MatrixXd column = exact_robot_column(esdf.information());
  const Eigen::MatrixXd sigma_rr = exact.marginal(0);
  for (int i = 1; i < esdf.num_blocks(); ++i) {
    core::LinkProposal p;
    if (!slam.bounds().propose(i, slam.recovery().cross_covariance(i), &p).ok()) continue;
    const core::Vec6 x_r = robot.head<6>();
    const core::Vec6 x_i = mean.segment<6>(Eigen::Index{i} * kD);
    LogdetRow row;
    row.state_i = 0;
    row.state_j = i;
    Eigen::MatrixXd exact_joint(2 * kD, 2 * kD);
    const Eigen::MatrixXd sigma_ir = column.middleRows(Eigen::Index{i} * kD, kD);
    exact_joint << sigma_rr, sigma_ir.transpose(), sigma_ir, exact.marginal(i);
    const core::Mat6 exact_rel = core::relative_pose_covariance(pose_joint(exact_joint), x_r, x_i);
    row.ours = logdet_or_nan(core::relative_pose_covariance(pose_joint(p.joint), x_r, x_i),
                             exact_rel);
    try {
      const core::MarkovBlanketResult mb = core::markov_blanket_joint(esdf.information(), 0, i);
      row.markov_blanket = logdet_or_nan(
          core::relative_pose_covariance(pose_joint(mb.joint), x_r, x_i), exact_rel);
    } catch (const std::exception&) {
      row.markov_blanket = std::numeric_limits<double>::quiet_NaN();
    }
    a.logdet.push_back(row);
  }
}

}  // namespace

ReplayAnalysis analyse(NavFilter& slam) {
  ReplayAnalysis a;
  const auto start = std::chrono::steady_clock::now();
  if (!slam.initialised()) {
    a.error = "the filter never initialised (no attitude, heading and depth in the log)";
    return a;
  }
  slam.recover_now();
  core::Esdf esdf = slam.esdf();
  if (core::Status s = esdf.recover_mean_direct(); !s.ok()) {
    a.error = "final mean: " + s.to_string();
    return a;
  }
  const Eigen::VectorXd& mean = esdf.mean();
  a.robot_mean = mean.head<12>();
  try {
    const core::ExactMarginals exact =
        core::ExactMarginals::compute(esdf.information().to_sparse(), kD);
    int conservative = 0;
    for (int b = 1; b < esdf.num_blocks(); ++b) {
      StateCheck s;
      s.state = b;
      s.image = slam.image_of_state(b);
      s.mean = mean.segment<12>(Eigen::Index{b} * kD);
      s.bound = slam.bounds().bound(b).topLeftCorner(6, 6);
      s.exact = exact.marginal(b).topLeftCorner(6, 6);
      if (s.image) s.initial_bound = s.image->initial_bound;
      s.conservative = core::is_conservative(s.bound, s.exact, kConservativeTolerance);
      conservative += s.conservative ? 1 : 0;
      a.states.push_back(s);
    }
    a.conservative_fraction =
        a.states.empty() ? 0.0 : static_cast<double>(conservative) / a.states.size();
    logdet_rows(slam, exact, a.robot_mean, mean, a);
  } catch (const std::exception& e) {
    a.error = std::string("exact marginals: ") + e.what();
  }
  a.analysis_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return a;
}

namespace {

nlohmann::json pose_json(const core::Vec12& x) {
  return {{"x_m", x(0)},         {"y_m", x(1)},         {"z_m", x(2)},
          {"roll_rad", x(3)},    {"pitch_rad", x(4)},   {"heading_rad", x(5)}};
}

/// The robot's running pose, or null while the filter has no state yet (e.g. the
/// dead-reckoning twin of a resumed replay stopped before its first measurements).
nlohmann::json robot_pose_json(const core::Esdf& filter) {
  if (!filter.initialized()) return nullptr;
  return pose_json(filter.mean().head<12>());
}

}  // namespace

std::string replay_summary_json(const ReplayRun& run, const ReplayAnalysis& analysis,
                                const std::string& dive_dir, const std::string& config_path) {
  const NavFilterCounters& c = run.slam->counters();
  nlohmann::json j;
  j["dive_dir"] = dive_dir;
  j["log"] = run.log_path;
  j["config"] = config_path;
  j["images"] = c.images;
  j["delayed_states"] = run.slam->esdf().num_blocks() - 1;
  j["camera_links"] = c.links_accepted;
  j["wall_s"] = run.wall_s;
  j["log_span_s"] = run.log_span_s;
  j["realtime_factor"] = run.wall_s > 0.0 ? run.log_span_s / run.wall_s : 0.0;
  j["analysis_s"] = analysis.analysis_s;
  j["final_pose"] = pose_json(analysis.robot_mean);
  j["final_pose_running"] = robot_pose_json(run.slam->esdf());
  if (run.dead_reckoning) {
    j["dead_reckoning_final_pose"] = robot_pose_json(run.dead_reckoning->esdf());
  }
  j["max_cg_relative_residual"] = c.max_cg_relative_residual;
  j["cg_iterations_per_image"] = run.slam->options().recovery.iterations_per_step;
  j["recovery"] = run.slam->options().recovery_thread
                      ? "recovery thread, taken at data time image + recovery_handoff_s "
                        "(deterministic)"
                      : "synchronous at each image (deterministic)";
  j["candidates"] = c.candidates;
  j["links_proposed"] = c.links_proposed;
  j["links_accepted"] = c.links_accepted;
  j["links_gated"] = c.links_gated;
  j["registration_failed"] = c.registration_failed;
  j["not_registered"] = c.not_registered;
  j["outliers_rejected"] = c.outliers_rejected;
  j["outliers_accepted"] = c.outliers_accepted;
  j["camera_gate_chi2_5dof"] = run.slam->options().camera_gate_chi2;
  j["registrations"] = run.registrations->size();
  j["registration_outliers"] = run.registrations->outliers();
  j["conservative_fraction"] = analysis.conservative_fraction;
  j["states_checked"] = analysis.states.size();
  j["measurements"] = c.measurements;
  j["updates"] = c.updates;
  j["update_failures"] = c.update_failures;
  j["recovery_failures"] = c.recovery_failures;
  j["bound_update_failures"] = c.bound_update_failures;
  j["before_initialisation"] = c.before_initialisation;
  j["decode_errors"] = run.source.decode_errors;
  j["late_dropped"] = run.ordering.dropped_late;
  j["ordering_full_dropped"] = run.ordering.dropped_full;
  j["error"] = run.error.empty() ? analysis.error : run.error;
  return j.dump();
}

namespace {

std::FILE* open_or_throw(const std::filesystem::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error("cannot write " + path.string());
  return f;
}

void write_trajectory(const std::vector<ImageRecord>& images, const std::filesystem::path& path) {
  std::FILE* f = open_or_throw(path);
  std::fprintf(f, "t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad,var_x,var_y,var_z,var_heading\n");
  for (const ImageRecord& r : images) {
    const core::Vec12& x = r.robot_mean;
    const core::Mat12& P = r.robot_covariance;
    std::fprintf(f, "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                 static_cast<long long>(r.t_us), x(0), x(1), x(2), x(3), x(4), x(5), P(0, 0),
                 P(1, 1), P(2, 2), P(5, 5));
  }
  std::fclose(f);
}

void write_matrix(std::FILE* f, const Eigen::Matrix<double, 6, 6>& m) {
  for (int a = 0; a < 6; ++a) {
    for (int b = 0; b < 6; ++b) std::fprintf(f, ",%.17g", m(a, b));
  }
}

void write_states(const ReplayAnalysis& a, const std::filesystem::path& path) {
  std::FILE* f = open_or_throw(path);
  std::fprintf(f, "state_id,frame_id,t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad");
  for (const char* prefix : {"b", "e", "i"}) {
    for (int k = 0; k < 36; ++k) std::fprintf(f, ",%s%d%d", prefix, k / 6, k % 6);
  }
  std::fprintf(f, "\n");
  for (const StateCheck& s : a.states) {
    std::fprintf(f, "%d,%lld,%lld", s.state,
                 s.image ? static_cast<long long>(s.image->frame_id) : -1LL,
                 s.image ? static_cast<long long>(s.image->t_us) : -1LL);
    for (int k = 0; k < 6; ++k) std::fprintf(f, ",%.17g", s.mean(k));
    write_matrix(f, s.bound);
    write_matrix(f, s.exact);
    write_matrix(f, s.initial_bound);
    std::fprintf(f, "\n");
  }
  std::fclose(f);
}

void write_links(const std::vector<LinkRecord>& links, const std::filesystem::path& path) {
  std::FILE* f = open_or_throw(path);
  std::fprintf(f, "t_us,frame_i,frame_j,state_i,state_j,outcome,mahalanobis_sq,is_outlier\n");
  for (const LinkRecord& l : links) {
    std::fprintf(f, "%lld,%llu,%llu,%d,%d,%s,", static_cast<long long>(l.t_us),
                 static_cast<unsigned long long>(l.frame_i),
                 static_cast<unsigned long long>(l.frame_j), l.state_i, l.state_j,
                 to_string(l.outcome));
    if (l.mahalanobis_sq >= 0.0) std::fprintf(f, "%.17g", l.mahalanobis_sq);
    std::fprintf(f, ",%d\n", l.is_outlier ? 1 : 0);
  }
  std::fclose(f);
}

void write_proposals(const std::vector<ProposalRecord>& rows, const std::filesystem::path& path) {
  std::FILE* f = open_or_throw(path);
  std::fprintf(f, "frame_id,candidates,proposed,accepted\n");
  for (const ProposalRecord& r : rows) {
    std::fprintf(f, "%llu,%d,%d,%d\n", static_cast<unsigned long long>(r.frame_id), r.candidates,
                 r.proposed, r.accepted);
  }
  std::fclose(f);
}

void write_information_blocks(const core::InformationMatrix& info,
                              const std::filesystem::path& path) {
  std::FILE* f = open_or_throw(path);
  std::fprintf(f, "# block_dim %d num_blocks %d\ni,j\n", info.block_dim(), info.num_blocks());
  for (int i = 0; i < info.num_blocks(); ++i) {
    std::fprintf(f, "%d,%d\n", i, i);
    for (int k = 0; k < info.num_neighbours(i); ++k) {
      const int j = info.neighbour(i, k);
      if (i < j) std::fprintf(f, "%d,%d\n", i, j);
    }
  }
  std::fclose(f);
}

void write_logdet(const std::vector<LogdetRow>& rows, const std::filesystem::path& path) {
  std::FILE* f = open_or_throw(path);
  std::fprintf(f, "state_i,state_j,ours,markov_blanket\n");
  for (const LogdetRow& r : rows) {
    std::fprintf(f, "%d,%d,%.17g,%.17g\n", r.state_i, r.state_j, r.ours, r.markov_blanket);
  }
  std::fclose(f);
}

}  // namespace

void write_replay_outputs(const ReplayRun& run, const ReplayAnalysis& analysis,
                          const std::string& summary_json, const std::string& dir) {
  const std::filesystem::path out(dir);
  std::filesystem::create_directories(out);
  {
    std::ofstream summary(out / "summary.json");
    if (!(summary << summary_json << "\n")) {
      throw std::runtime_error("cannot write " + (out / "summary.json").string());
    }
  }
  write_trajectory(run.slam->images(), out / "trajectory.csv");
  if (run.dead_reckoning) write_trajectory(run.dead_reckoning->images(), out / "dead_reckoning.csv");
  write_states(analysis, out / "states.csv");
  write_links(run.slam->links(), out / "links.csv");
  write_proposals(run.slam->proposals(), out / "proposals.csv");
  write_information_blocks(run.slam->esdf().information(), out / "information_blocks.csv");
  write_logdet(analysis.logdet, out / "logdet.csv");
}

}  // namespace nav::daemon
