// navtool covariance: replays a g2o pose graph as the delayed-state filter (core/posegraph/
// replay.h) with per-step state recovery (PCG or direct) and the Algorithm 1 covariance bounds
// of Eustice et al. (RSS 2005), then checks every bound against exact marginals and compares
// with the Markov-blanket approximation (paper Fig. 3). Times each phase with a steady clock
// (core has no clocks). --json prints one JSON object on stdout; otherwise a summary on stderr.
// Malformed input: error naming the line, exit status 1.
#include <sys/resource.h>
#include <time.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "nav/core/posegraph/g2o.h"
#include "nav/core/posegraph/replay.h"
#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/core/recovery/state_recovery.h"
#include "nav/core/recovery/time_of_use.h"
#include "navtool/commands.h"
#include "nav/report/csv_table.h"
#include "nav/report/figures.h"

namespace nav::tool {
namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

/// Steps between the kept factor's exact-marginal renewals when --refresh-interval is not given.
/// Longer intervals make the step cheaper and the bounds between renewals looser; 20 is the
/// trade-off measured on parking-garage (docs/performance.md "The covariance tool's default
/// recovery").
constexpr int kKeptRefreshInterval = 20;

struct CovarianceArgs {
  std::string file;
  int iterations = 5;
  double tolerance = 0.0;
  int max_iterations = core::StateRecoveryOptions{}.max_iterations;  ///< --tolerance cap per step
  bool direct = false;
  bool json = false;
  bool no_certify = false;
  bool no_old_state_energy = false;
  bool csr = false;
  std::string kernel = "packed";
  bool no_markov_blanket = false;
  int histogram_bins = 20;
  double conservative_tolerance = 1e-9;
  std::string figure;  ///< Fig. 3 PNG path (empty: none)
  /// The kept factor: tight bounds at a third of the factor's step (docs/performance.md
  /// "The covariance tool's default recovery").
  std::string preconditioner = "kept-factor";
  /// 0: the preconditioner's own default. The kept factor renews the exact marginals every
  /// kKeptRefreshInterval steps (the refresh does not refactor it); the factor refactors every
  /// step (the library's default), or its stale M leaves the bounds loose (docs/consistency.md
  /// "K3 and the floor at the time of use").
  int refresh_interval = 0;
  double refresh_residual = core::StateRecoveryOptions{}.refresh_residual;
  int iterations_after_refresh = core::StateRecoveryOptions{}.iterations_after_refresh;
  double rounding_margin = core::BoundsOptions{}.rounding_margin;
  int checks = 100;  ///< time-of-use check times spread over the run
};

double elapsed_ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

/// CPU time of the whole process, every thread (CHOLMOD's BLAS may use more than one).
double process_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

/// CPU time of the calling thread (excludes time preempted by other processes).
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = p * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<size_t>(std::floor(pos));
  const auto hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

double mean(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

json nan_as_null(double v) { return std::isnan(v) ? json(nullptr) : json(v); }

json stats_json(const std::vector<double>& values) {
  if (values.empty()) return json{{"min", nullptr}, {"median", nullptr}, {"max", nullptr}};
  const core::SummaryStats s = core::summarize(values);
  return json{{"min", s.min}, {"median", s.median}, {"max", s.max}, {"count", s.count}};
}

/// Common bins over both distributions (paper Fig. 3 histograms).
json histogram_json(const std::vector<double>& ours, const std::vector<double>& mb, int bins) {
  std::vector<double> all = ours;
  all.insert(all.end(), mb.begin(), mb.end());
  if (all.empty() || bins < 1) return json::object();
  double lo = *std::min_element(all.begin(), all.end());
  double hi = *std::max_element(all.begin(), all.end());
  if (hi <= lo) hi = lo + 1.0;
  const double width = (hi - lo) / bins;
  auto count = [&](const std::vector<double>& v) {
    std::vector<int> c(static_cast<size_t>(bins), 0);
    for (double x : v) {
      const int b = std::clamp(static_cast<int>((x - lo) / width), 0, bins - 1);
      ++c[static_cast<size_t>(b)];
    }
    return c;
  };
  std::vector<double> edges;
  for (int b = 0; b <= bins; ++b) edges.push_back(lo + b * width);
  return json{{"quantity", "log det(bound) - log det(exact) per delayed state"},
              {"bin_edges", edges},
              {"ours", count(ours)},
              {"markov_blanket", count(mb)}};
}

core::ReplayOptions replay_options(const CovarianceArgs& a) {
  core::ReplayOptions o;
  if (a.direct) {
    o.recovery.mode = core::RecoveryMode::kDirect;
  } else if (a.tolerance > 0.0) {
    o.recovery.mode = core::RecoveryMode::kTolerance;
    o.recovery.relative_tolerance = a.tolerance;
    o.recovery.max_iterations = a.max_iterations;
  } else {
    o.recovery.mode = core::RecoveryMode::kFixedIterations;
    o.recovery.iterations_per_step = a.iterations;
  }
  o.recovery.kernel =
      a.kernel == "generic" ? core::RecoveryKernel::kGeneric : core::RecoveryKernel::kPacked;
  o.recovery.preconditioner = a.preconditioner == "block-jacobi"
                                  ? core::RecoveryPreconditioner::kBlockJacobi
                                  : core::RecoveryPreconditioner::kFactor;
  o.recovery.keep_factor_equal = a.preconditioner == "kept-factor";
  o.recovery.refresh_interval = a.refresh_interval > 0 ? a.refresh_interval
                                : o.recovery.keep_factor_equal
                                    ? kKeptRefreshInterval
                                    : core::StateRecoveryOptions{}.refresh_interval;
  o.recovery.refresh_residual = a.refresh_residual;
  o.recovery.iterations_after_refresh = a.iterations_after_refresh;
  o.bounds.certify_truncation = !a.no_certify;
  o.bounds.old_state_energy = !a.no_old_state_energy;
  o.bounds.rounding_margin = a.rounding_margin;
  o.recovery_operator =
      a.csr ? core::RecoveryOperator::kCsrSnapshot : core::RecoveryOperator::kInformationMatrix;
  return o;
}

void run_covariance(const CovarianceArgs& args) {
  core::PoseGraph graph;
  try {
    graph = core::read_g2o(args.file);
  } catch (const core::G2oError& e) {
    throw CommandError(std::string("covariance: ") + e.what());
  }
  const core::ReplayOptions options = replay_options(args);
  core::PoseGraphReplay replay(graph, options);
  if (core::Status s = replay.start(); !s.ok()) {
    throw CommandError("covariance: " + args.file + ": " + s.to_string());
  }
  std::vector<double> recovery_ms, recovery_cpu_ms, bounds_us_per_link;
  std::vector<double> refresh_cpu_ms, between_refreshes_cpu_ms;
  double max_relative_residual = 0.0;
  std::vector<double> relative_residuals;
  int steps = 0, capped_steps = 0, refreshes = 0;
  std::vector<double> iterations;
  core::TimeOfUseStats time_of_use;
  const core::TimeOfUseOptions time_of_use_options{args.conservative_tolerance,
                                                   !args.no_markov_blanket};
  const int check_every = std::max(1, (replay.num_vertices() - 1) / std::max(1, args.checks));
  while (!replay.done()) {
    const int vertex = replay.next_vertex();
    auto fail = [&](const core::Status& s) {
      throw CommandError("covariance: " + args.file + ": step for vertex " +
                         std::to_string(graph.vertices[static_cast<size_t>(vertex)].id) + ": " +
                         s.to_string());
    };
    if (core::Status s = replay.predict(); !s.ok()) fail(s);
    auto t0 = Clock::now();
    const double cpu0 = thread_cpu_ms();
    const core::RecoveryResult r = replay.recover();
    recovery_cpu_ms.push_back(thread_cpu_ms() - cpu0);
    recovery_ms.push_back(elapsed_ms(t0));
    if (!r.status.ok()) fail(r.status);
    max_relative_residual = std::max(max_relative_residual, r.max_relative_residual);
    relative_residuals.push_back(r.max_relative_residual);
    if (r.hit_iteration_cap) ++capped_steps;
    refreshes += r.refreshed ? 1 : 0;
    (r.refreshed ? refresh_cpu_ms : between_refreshes_cpu_ms).push_back(recovery_cpu_ms.back());
    iterations.push_back(r.iterations);
    if (args.checks > 0 && vertex % check_every == 0) {
      try {
        core::check_time_of_use(replay.filter(), replay.bounds(), replay.recovery(),
                                time_of_use_options, time_of_use);
      } catch (const std::exception& e) {
        throw CommandError("covariance: time-of-use check at vertex " + std::to_string(vertex) +
                           ": " + e.what());
      }
    }
    const int links = replay.current_links();
    t0 = Clock::now();
    if (core::Status s = replay.update_bounds(); !s.ok()) fail(s);
    if (links > 0) bounds_us_per_link.push_back(1000.0 * elapsed_ms(t0) / links);
    if (core::Status s = replay.apply_links(); !s.ok()) fail(s);
    ++steps;
  }

  const Eigen::SparseMatrix<double> lambda = replay.filter().information().to_sparse();
  auto t0 = Clock::now();
  const double exact_cpu0 = process_cpu_ms();
  std::unique_ptr<core::ExactMarginals> exact;
  try {
    exact = std::make_unique<core::ExactMarginals>(core::ExactMarginals::compute(lambda, 6));
  } catch (const std::exception& e) {
    throw CommandError("covariance: exact marginals of the final information matrix: " +
                       std::string(e.what()));
  }
  const double exact_ms = elapsed_ms(t0);
  const double exact_cpu_ms = process_cpu_ms() - exact_cpu0;
  const core::BoundsCheck check = core::check_bounds(replay, *exact, args.conservative_tolerance,
                                                     !args.no_markov_blanket);
  const double dim = static_cast<double>(lambda.rows());
  const size_t delayed = check.logdet_ratio_ours.size();

  json out;
  out["file"] = args.file;
  out["poses"] = graph.vertices.size();
  out["edges"] = graph.edges.size();
  out["planar"] = graph.planar;
  out["state_dim"] = lambda.rows();
  out["nnz_fraction"] = static_cast<double>(lambda.nonZeros()) / (dim * dim);
  out["steps"] = steps;
  out["mode"] = core::to_string(options.recovery.mode);
  out["iterations_per_step"] = options.recovery.mode == core::RecoveryMode::kFixedIterations
                                   ? json(options.recovery.iterations_per_step)
                                   : json(nullptr);
  const bool tolerance_mode = options.recovery.mode == core::RecoveryMode::kTolerance;
  out["relative_tolerance"] =
      tolerance_mode ? json(options.recovery.relative_tolerance) : json(nullptr);
  out["max_iterations_per_step"] =
      tolerance_mode ? json(options.recovery.max_iterations) : json(nullptr);
  out["capped_steps"] = capped_steps;
  out["preconditioner"] = core::to_string(options.recovery.preconditioner);
  out["kept_factor"] = options.recovery.keep_factor_equal;
  out["refreshes"] = refreshes;
  out["iterations_after_refresh"] = options.recovery.iterations_after_refresh;
  out["iterations_median"] = percentile(iterations, 0.5);
  out["time_of_use_checks"] = time_of_use.checks;
  out["time_of_use_check_every_steps"] = check_every;
  out["time_of_use_bounds_checked"] = time_of_use.bounds_checked;
  out["time_of_use_relative_pairs_singular"] = time_of_use.relative_pairs_singular;
  out["time_of_use_conservative_fraction"] =
      nan_as_null(time_of_use.bounds_conservative_fraction());
  out["time_of_use_joints_checked"] = time_of_use.joints_checked;
  out["time_of_use_joint_conservative_fraction"] =
      nan_as_null(time_of_use.joints_conservative_fraction());
  out["time_of_use_worst_min_eigenvalue"] = time_of_use.worst_min_eigenvalue;
  const std::vector<double> relative_mb = time_of_use.markov_blanket();
  out["logdet_ratio_relative_ours"] = stats_json(time_of_use.ours());
  out["logdet_ratio_relative_markov_blanket"] = stats_json(relative_mb);
  out["relative_markov_blanket_overconfident_fraction"] =
      relative_mb.empty() ? json(nullptr)
                          : json(static_cast<double>(time_of_use.markov_blanket_overconfident) /
                                 static_cast<double>(relative_mb.size()));
  out["certified_bounds"] = options.bounds.certify_truncation;
  out["certificate_old_state_energy"] = options.bounds.old_state_energy;
  out["rounding_margin"] = options.bounds.rounding_margin;
  out["operator"] = args.csr ? "csr-snapshot" : "information-matrix";
  out["kernel"] = core::to_string(options.recovery.kernel);
  out["broken_chain_vertices"] = replay.broken_chain_vertices();
  out["skipped_bound_updates"] = replay.skipped_bound_updates();
  out["recovery_ms_median"] = percentile(recovery_ms, 0.5);
  out["recovery_ms_p99"] = percentile(recovery_ms, 0.99);
  out["recovery_ms_max"] = percentile(recovery_ms, 1.0);
  out["recovery_cpu_ms_median"] = percentile(recovery_cpu_ms, 0.5);
  out["recovery_cpu_ms_p99"] = percentile(recovery_cpu_ms, 0.99);
  out["recovery_cpu_ms_mean"] = mean(recovery_cpu_ms);
  out["recovery_cpu_ms_refresh_median"] = percentile(refresh_cpu_ms, 0.5);
  out["recovery_cpu_ms_between_refreshes_median"] = percentile(between_refreshes_cpu_ms, 0.5);
  out["bounds_update_us_median"] = percentile(bounds_us_per_link, 0.5);
  out["exact_marginals_ms"] = exact_ms;
  out["exact_marginals_cpu_ms"] = exact_cpu_ms;
  out["exact_marginals_kernel"] = core::auto_marginals_kernel_name();
  out["max_relative_residual"] = max_relative_residual;
  out["relative_residual_median"] = percentile(relative_residuals, 0.5);
  out["final_relative_residual"] = relative_residuals.empty() ? 0.0 : relative_residuals.back();
  out["conservative_checked"] = check.checked;
  out["conservative_fraction"] =
      check.checked > 0 ? static_cast<double>(check.conservative) / check.checked : 0.0;
  out["worst_min_eigenvalue"] = check.worst_min_eigenvalue;
  out["not_positive_definite_bounds"] = check.not_positive_definite_bounds;
  out["conservative_tolerance"] = args.conservative_tolerance;
  out["logdet_ratio_ours"] = stats_json(check.logdet_ratio_ours);
  out["logdet_ratio_markov_blanket"] = stats_json(check.logdet_ratio_markov_blanket);
  out["markov_blanket_overconfident_fraction"] =
      args.no_markov_blanket || delayed == 0
          ? json(nullptr)
          : json(static_cast<double>(check.markov_blanket_overconfident) /
                 static_cast<double>(delayed));
  out["fig3_histogram"] = histogram_json(check.logdet_ratio_ours,
                                         check.logdet_ratio_markov_blanket, args.histogram_bins);
  if (!args.figure.empty()) {
    const std::string title = "Fig. 3  log det(bound) - log det(exact) per delayed state: " +
                              std::filesystem::path(args.file).filename().string();
    try {
      report::write_png(args.figure, report::logdet_histogram_figure(
                                         check.logdet_ratio_ours, check.logdet_ratio_markov_blanket,
                                         args.histogram_bins, title));
    } catch (const report::ReportError& e) {
      throw CommandError(std::string("covariance: --figure: ") + e.what());
    }
    out["figure"] = args.figure;
  }
  out["peak_rss_mb"] = peak_rss_mb();
  if (args.json) {
    std::cout << out.dump() << std::endl;
  } else {
    std::cerr << out.dump(2) << std::endl;
  }
}

void add_covariance(CLI::App& app) {
  auto args = std::make_shared<CovarianceArgs>();
  CLI::App* cmd = app.add_subcommand(
      "covariance",
      "Replay a g2o pose graph as the delayed-state filter (RSS 2005): per-vertex state "
      "recovery and Algorithm 1 covariance bounds, then every bound checked against exact "
      "marginals and the Markov blanket (Fig. 3).\n"
      "Vertex k is the new robot state, predicted with the odometry edge (k-1,k) (or (k,k-1), "
      "inverted); every other edge (j,k), j<k, is a camera link. Broken odometry chain: when "
      "k has no edge to k-1, the first edge (file order) joining k to an earlier vertex is "
      "applied as a link and k is predicted with F=0 and a diffuse process noise (variance "
      "1e6, a weak prior at the file's estimate); a vertex with no edge to an earlier vertex "
      "is an error naming it. Linearised at the file's estimates; gauge prior sigma 1e-3 on "
      "vertex 0.");
  cmd->add_option(
         "file", args->file,
         "g2o file (VERTEX_SE3:QUAT / EDGE_SE3:QUAT, or VERTEX_SE2 / EDGE_SE2 lifted to 3-D)")
      ->required();
  auto* iterations = cmd->add_option("--iterations", args->iterations,
                                     "fixed PCG iterations per step (default 5; real-time mode)")
                         ->check(CLI::NonNegativeNumber);
  auto* tolerance = cmd->add_option("--tolerance", args->tolerance,
                                    "iterate PCG to this relative residual instead")
                        ->check(CLI::PositiveNumber);
  auto* max_iterations =
      cmd->add_option("--max-iterations", args->max_iterations,
                      "with --tolerance: PCG iteration cap per step (default 5000). Reaching it "
                      "is not an error: the step keeps the residual reached (capped_steps, "
                      "max_relative_residual) and the certified bounds stay conservative")
          ->check(CLI::PositiveNumber);
  max_iterations->needs(tolerance);
  auto* direct = cmd->add_flag("--direct", args->direct, "direct CHOLMOD solve each step");
  iterations->excludes(tolerance)->excludes(direct);
  tolerance->excludes(direct);
  cmd->add_flag("--json", args->json, "one JSON object on stdout (else a summary on stderr)");
  cmd->add_flag("--no-certify", args->no_certify,
                "the paper's uninflated bounds (not conservative under truncated CG)");
  cmd->add_flag("--no-old-state-energy", args->no_old_state_energy,
                "certify with K1/K2 only, not with the factor's K3 (comparison)");
  cmd->add_flag("--csr", args->csr,
                "recover on a CSR snapshot per step instead of the block matrix");
  cmd->add_option("--kernel", args->kernel,
                  "PCG kernel on the block matrix: packed (SIMD, incremental preconditioner) or "
                  "generic (the original, for comparison)")
      ->check(CLI::IsMember({"packed", "generic"}));
  cmd->add_option("--preconditioner", args->preconditioner,
                  "recovery preconditioner: kept-factor (default: a factor kept equal to Λ by "
                  "row modifications and rank updates, one refinement step per image; the "
                  "refresh renews only the exact marginals), factor (Cholesky of Λ refreshed "
                  "every few steps) or block-jacobi")
      ->check(CLI::IsMember({"factor", "kept-factor", "block-jacobi"}));
  cmd->add_option("--refresh-interval", args->refresh_interval,
                  "steps between refreshes: kept-factor renews the exact marginals (default "
                  "20), factor refactors (default 1: every step)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--refresh-residual", args->refresh_residual,
                  "factor: refactor when the previous step's relative residual exceeded this")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--iterations-after-refresh", args->iterations_after_refresh,
                  "factor: at most this many PCG iterations in a step that refactored (default 1: "
                  "M = Λ then, one iteration is the direct solve)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--rounding-margin", args->rounding_margin,
                  "relative rounding margin τ: over the exact marginals of a refresh and as the "
                  "floor of the certificate's κ (default 1e-6; bounds.h)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--checks", args->checks,
                  "time-of-use checks (relative-pose Fig. 3, bounds vs exact) spread evenly "
                  "over the run (default 100; 0: none)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--no-markov-blanket", args->no_markov_blanket,
                "skip the Markov-blanket comparison");
  cmd->add_option("--bins", args->histogram_bins, "Fig. 3 histogram bins")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--figure", args->figure,
                  "write the Fig. 3 histogram (ours vs Markov blanket) as a PNG to this path");
  cmd->add_option("--conservative-tolerance", args->conservative_tolerance,
                  "relative tolerance of the PSD check of bound - exact")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([args] { run_covariance(*args); });
}

const CommandRegistration kRegister{"covariance", add_covariance};

}  // namespace
}  // namespace nav::tool
