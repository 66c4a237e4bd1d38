// What a sparse Cholesky factor kept equal to Λ would cost per recovery step, beside
// refactorising: the measurement behind the choice of recovery preconditioner
// (docs/performance.md "A factor kept equal to Λ").
//
// Method (Davis & Hager, "Modifying a sparse Cholesky factorization", SIMAX 1999; "Row
// modifications of a sparse Cholesky factorization", SIMAX 2005; CHOLMOD's Modify module): a
// simplicial LDLᵀ factor of Λ over the states present, sized in advance for `kAppended` more
// states whose rows are still the identity and are ordered last (CHOLMOD's own order of the
// present states, then the future ones chronologically, so a new state's rows enter at the
// end). Arguments: the number of states and the link graph (survey_links: 1.5 or 6 links per
// state). Each
// benchmark iteration is one image of a survey, with the robot as the last block (linked to the
// newest state by W, as the robot's odometry couples it to the state kept last):
//   * trailing: the robot's and the previous newest state's rows and columns deleted
//     (cholmod_rowdel) and the newest re-added without the robot's odometry, then the robot
//     re-added linked to the new state: in the filter both change at every prediction, not
//     only by PSD terms (marginalising the previous robot changes the newest state's block);
//   * row-add: the new state's d rows and columns (its link couplings to the present states and
//     its own diagonal block), one cholmod_rowadd per scalar row;
//   * update: the link information on the older endpoints' diagonal blocks, C Cᵀ with
//     C = W^½ on the rows of each older endpoint (cholmod_updown, rank d per link);
//   * solve: Λ X = B for the 1 + d columns of the recovery ([η | E_r]) with the modified factor.
// Λ uses identity link Jacobians ([W −W; −W W] per link, W a dense 6 x 6 information of the
// scale of lawnmower_graph.h's, a prior W on state 0): the block pattern and scale of the
// survey graph, with increments that are exact to apply. After the timed steps the factor's
// solve is checked against Λ assembled from scratch (relative residual <= 1e-8, else the
// benchmark errors), and a supernodal factorisation plus selected inversion of the same Λ
// (ExactMarginals, what a refresh costs today), its 13-column solve and a step of navd's default
// recovery (block-Jacobi PCG, five iterations) are timed for comparison (the second of two
// calls each).
// Counters (per step): trailing_ms, rowadd_ms, update_ms, solve_ms, links; refresh_factor_ms,
// refresh_inversion_ms, supernodal_solve_ms, block_jacobi_step_ms once; nnz_L of both
// factors.
#include <benchmark/benchmark.h>
#include <cholmod.h>

#include <Eigen/Cholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "lawnmower_graph.h"
#include "nav/core/filter/information_matrix.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/core/recovery/state_recovery.h"

namespace nav::core {
namespace {

constexpr int kD = 6;
constexpr int kAppended = 128;  // states appended by row-add in one benchmark run

struct Link {
  int older = 0, newer = 0;
};

/// The lawnmower survey of about `states` poses as links between state indices, sorted by newer:
/// lawnmower_graph.h's (odometry, and a link to the pose beside every second pose on the
/// previous line: 1.5 links per state), or with `dense` a link from every pose to the five
/// poses nearest beside it on the previous line (6 per state, the default survey has 7.5 camera
/// links per image).
std::vector<Link> survey_links(int states, bool dense) {
  const int rows = states <= 1000 ? 20 : states <= 10000 ? 50 : 200;  // as preconditioner_bench
  const int cols = states / rows;
  std::vector<Link> links;
  if (!dense) {
    const PoseGraph graph = bench::lawnmower_graph(rows, cols);
    for (const G2oEdge& e : graph.edges) {
      links.push_back({std::min(e.from_index, e.to_index), std::max(e.from_index, e.to_index)});
    }
  } else {
    for (int k = 1; k < rows * cols; ++k) links.push_back({k - 1, k});
    for (int r = 1; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        const int beside = cols - 1 - c;  // the previous line runs the other way
        for (int o = std::max(0, beside - 2); o <= std::min(cols - 1, beside + 2); ++o) {
          const int older = (r - 1) * cols + o, newer = r * cols + c;
          if (older != newer - 1) links.push_back({older, newer});  // not the odometry again
        }
      }
    }
  }
  std::sort(links.begin(), links.end(), [](const Link& a, const Link& b) {
    return a.newer != b.newer ? a.newer < b.newer : a.older < b.older;
  });
  return links;
}

/// A dense SPD link information: lawnmower_graph.h's (10 cm, ~1 deg) seen through a fixed
/// mixing of the coordinates, so that every block is full as in the filter's Λ (a diagonal W
/// would split Λ into six scalar graphs and flatter the simplicial factor).
Mat6 link_information() {
  Vec6 diagonal;
  diagonal << 100.0, 100.0, 100.0, 3.0e3, 3.0e3, 3.0e3;
  Mat6 mix = Mat6::Identity();
  for (int i = 0; i < kD; ++i) {
    for (int j = 0; j < kD; ++j) mix(i, j) += 0.1 * (i + 1) / (j + 2);
  }
  return mix * diagonal.asDiagonal() * mix.transpose();
}

/// Λ over `n_states` state blocks and the robot (block n_states) with the links whose newer end
/// is below `present`; the robot is linked to state present − 1 by W (the newest state's
/// odometry); state blocks from `present` on are the identity (rows not yet added).
InformationMatrix assemble(const std::vector<Link>& links, int n_states, int present) {
  const Mat6 w = link_information();
  InformationMatrix lambda(kD);
  for (int b = 0; b <= n_states; ++b) lambda.add_block();
  auto add_link = [&](int a, int b) {
    lambda.add_to_block(a, a, w);
    lambda.add_to_block(b, b, w);
    lambda.add_to_block(a, b, -w);
  };
  lambda.add_to_block(0, 0, w);  // the gauge: a prior on state 0
  for (const Link& l : links) {
    if (l.newer >= present) break;
    add_link(l.older, l.newer);
  }
  add_link(present - 1, n_states);
  for (int s = present; s < n_states; ++s) lambda.add_to_block(s, s, Mat6::Identity());
  return lambda;
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// One step of navd's default recovery (block-Jacobi PCG, 5 iterations, packed kernel) on Λ,
/// the second of two from a zero start: ms.
double block_jacobi_step_ms(const InformationMatrix& lambda, const Eigen::VectorXd& eta) {
  StateRecoveryOptions options;
  options.preconditioner = RecoveryPreconditioner::kBlockJacobi;
  StateRecovery recovery(kD, options);
  (void)recovery.set_solution(Eigen::MatrixXd::Zero(lambda.dim(), 1 + kD));
  (void)recovery.solve(lambda, eta);
  const auto t0 = std::chrono::steady_clock::now();
  (void)recovery.solve(lambda, eta);
  return ms_since(t0);
}

/// CHOLMOD view of the lower triangle (stype -1), copied.
cholmod_sparse* to_cholmod_lower(const Eigen::SparseMatrix<double>& a, cholmod_common* c) {
  const Eigen::SparseMatrix<double> lower = a.triangularView<Eigen::Lower>();
  cholmod_sparse* s = cholmod_allocate_sparse(
      lower.rows(), lower.cols(), static_cast<size_t>(lower.nonZeros()), 1, 1, -1, CHOLMOD_REAL, c);
  std::copy_n(lower.outerIndexPtr(), lower.cols() + 1, static_cast<int*>(s->p));
  std::copy_n(lower.innerIndexPtr(), lower.nonZeros(), static_cast<int*>(s->i));
  std::copy_n(lower.valuePtr(), lower.nonZeros(), static_cast<double*>(s->x));
  return s;
}

/// A packed n x cols sparse matrix from (row, col, value) entries, duplicates summed (two
/// links between the same states), rows sorted per column.
cholmod_sparse* to_cholmod(std::vector<Eigen::Triplet<double>> triplets, size_t n, int cols,
                           cholmod_common* c) {
  std::sort(triplets.begin(), triplets.end(), [](const auto& a, const auto& b) {
    return a.col() != b.col() ? a.col() < b.col() : a.row() < b.row();
  });
  std::vector<Eigen::Triplet<double>> entries;
  for (const auto& e : triplets) {
    if (!entries.empty() && entries.back().row() == e.row() && entries.back().col() == e.col()) {
      entries.back() = {e.row(), e.col(), entries.back().value() + e.value()};
    } else {
      entries.push_back(e);
    }
  }
  cholmod_sparse* s = cholmod_allocate_sparse(n, static_cast<size_t>(cols), entries.size(), 1, 1, 0,
                                              CHOLMOD_REAL, c);
  auto* p = static_cast<int*>(s->p);
  auto* i = static_cast<int*>(s->i);
  auto* x = static_cast<double*>(s->x);
  std::fill_n(p, cols + 1, 0);
  for (size_t e = 0; e < entries.size(); ++e) {
    ++p[entries[e].col() + 1];
    i[e] = entries[e].row();
    x[e] = entries[e].value();
  }
  std::partial_sum(p, p + cols + 1, p);
  return s;
}

/// The simplicial factor being modified, with the ordering that puts future states last.
struct ModifiedFactor {
  cholmod_common c{};
  cholmod_factor* L = nullptr;
  std::vector<int> inverse;  // inverse[original] = permuted

  ModifiedFactor(const Eigen::SparseMatrix<double>& lambda, int present_dim) {
    cholmod_start(&c);
    // CHOLMOD's own order (AMD) of the present states.
    const Eigen::SparseMatrix<double> head = lambda.topLeftCorner(present_dim, present_dim);
    cholmod_sparse* h = to_cholmod_lower(head, &c);
    cholmod_factor* symbolic = cholmod_analyze(h, &c);
    std::vector<int> perm(static_cast<size_t>(lambda.rows()));
    std::copy_n(static_cast<const int*>(symbolic->Perm), present_dim, perm.begin());
    std::iota(perm.begin() + present_dim, perm.end(), present_dim);
    cholmod_free_factor(&symbolic, &c);
    cholmod_free_sparse(&h, &c);
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_GIVEN;
    c.postorder = 0;
    c.supernodal = CHOLMOD_SIMPLICIAL;
    c.final_ll = 0;
    cholmod_sparse* a = to_cholmod_lower(lambda, &c);
    L = cholmod_analyze_p(a, perm.data(), nullptr, 0, &c);
    cholmod_factorize(a, L, &c);
    cholmod_free_sparse(&a, &c);
    inverse.resize(perm.size());
    for (size_t k = 0; k < perm.size(); ++k) {
      inverse[static_cast<size_t>(perm[k])] = static_cast<int>(k);
    }
  }
  ~ModifiedFactor() {
    cholmod_free_factor(&L, &c);
    cholmod_finish(&c);
  }
  ModifiedFactor(const ModifiedFactor&) = delete;
  ModifiedFactor& operator=(const ModifiedFactor&) = delete;

  int row(int state, int j) const { return inverse[static_cast<size_t>(state * kD + j)]; }
  bool ok() const { return c.status == CHOLMOD_OK && L != nullptr; }
};

/// Row-adds block s (its rows are the identity): Λ_{o s} = coupling for each (o, coupling), o
/// a block already present, and Λ_ss = diagonal; one cholmod_rowadd per scalar row.
void add_block(ModifiedFactor& f, int s, const std::vector<std::pair<int, Mat6>>& couplings,
               const Mat6& diagonal) {
  for (int j = 0; j < kD; ++j) {
    std::vector<Eigen::Triplet<double>> column;
    for (const auto& [o, coupling] : couplings) {
      for (int i = 0; i < kD; ++i) column.emplace_back(f.row(o, i), 0, coupling(i, j));
    }
    for (int i = 0; i <= j; ++i) column.emplace_back(f.row(s, i), 0, diagonal(i, j));
    cholmod_sparse* r = to_cholmod(std::move(column), f.L->n, 1, &f.c);
    cholmod_rowadd(static_cast<size_t>(f.row(s, j)), r, f.L, &f.c);
    cholmod_free_sparse(&r, &f.c);
  }
}

/// Sets the rows and columns of block s back to the identity (cholmod_rowdel per scalar row).
void delete_block(ModifiedFactor& f, int s) {
  for (int j = 0; j < kD; ++j) {
    cholmod_rowdel(static_cast<size_t>(f.row(s, j)), nullptr, f.L, &f.c);
  }
}

/// Row-adds state s with its links `first` .. `last` (newer == s): −W to each older end and
/// Σ W (+ `extra` on the diagonal).
void add_state(ModifiedFactor& f, int s, const Link* first, const Link* last, const Mat6& w,
               const Mat6& extra) {
  std::vector<std::pair<int, Mat6>> couplings;
  Mat6 diagonal = extra;
  for (const Link* l = first; l != last; ++l) {
    couplings.emplace_back(l->older, -w);
    diagonal += w;
  }
  add_block(f, s, couplings, diagonal);
}

/// Adds W to the diagonal block of each older endpoint: C = W^½ on its rows, rank d per link.
void update_older(ModifiedFactor& f, const Link* first, const Link* last, const Mat6& w_sqrt) {
  std::vector<Eigen::Triplet<double>> entries;
  int col = 0;
  for (const Link* l = first; l != last; ++l, col += kD) {
    for (int j = 0; j < kD; ++j) {
      for (int i = 0; i < kD; ++i) {
        if (w_sqrt(i, j) != 0.0) entries.emplace_back(f.row(l->older, i), col + j, w_sqrt(i, j));
      }
    }
  }
  cholmod_sparse* cc = to_cholmod(std::move(entries), f.L->n, col, &f.c);
  cholmod_updown(1, cc, f.L, &f.c);
  cholmod_free_sparse(&cc, &f.c);
}

/// The links whose newer end is state s, as [first, last).
std::pair<const Link*, const Link*> links_of(const std::vector<Link>& links, int s) {
  auto first = std::lower_bound(links.begin(), links.end(), s,
                                [](const Link& l, int t) { return l.newer < t; });
  auto last = first;
  while (last != links.end() && last->newer == s) ++last;
  const Link* base = links.data();
  return {base + (first - links.begin()), base + (last - links.begin())};
}

void BM_FactorKeptEqual(benchmark::State& state) {
  const int states = static_cast<int>(state.range(0));
  const std::vector<Link> links = survey_links(states, state.range(1) != 0);
  const int n_states = links.back().newer + 1;
  const int robot = n_states;  // the last block, ordered last
  const int present = n_states - kAppended;
  const Mat6 w = link_information();
  const Mat6 w_sqrt = Eigen::LLT<Mat6>(w).matrixL();  // W = w_sqrt w_sqrtᵀ
  ModifiedFactor f(assemble(links, n_states, present).to_sparse(), present * kD);
  if (!f.ok()) state.SkipWithError("CHOLMOD could not factor the initial Λ");
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Random((n_states + 1) * kD, 1 + kD);
  cholmod_dense b{};
  b.nrow = b.d = static_cast<size_t>(rhs.rows());
  b.ncol = static_cast<size_t>(rhs.cols());
  b.nzmax = static_cast<size_t>(rhs.size());
  b.x = rhs.data();
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  double trailing_ms = 0, rowadd_ms = 0, update_ms = 0, solve_ms = 0, link_count = 0;
  int t = present;
  for (auto _ : state) {
    if (t >= n_states) {
      state.SkipWithError("more iterations than appended states");
      break;
    }
    // The robot and the previous newest state change at every prediction: delete and re-add
    // (the newest without the robot's odometry, which moves on to state t).
    auto t0 = std::chrono::steady_clock::now();
    delete_block(f, robot);
    delete_block(f, t - 1);
    const auto [prev_first, prev_last] = links_of(links, t - 1);
    add_state(f, t - 1, prev_first, prev_last, w, Mat6::Zero());  // t - 1 > 0: no prior
    trailing_ms += ms_since(t0);
    const auto [first, last] = links_of(links, t);
    t0 = std::chrono::steady_clock::now();
    add_state(f, t, first, last, w, w);  // + the robot's odometry
    rowadd_ms += ms_since(t0);
    t0 = std::chrono::steady_clock::now();
    update_older(f, first, last, w_sqrt);
    update_ms += ms_since(t0);
    t0 = std::chrono::steady_clock::now();
    add_block(f, robot, {{t, -w}}, w);
    trailing_ms += ms_since(t0);
    t0 = std::chrono::steady_clock::now();
    cholmod_dense* x = cholmod_solve(CHOLMOD_A, f.L, &b, &f.c);
    solve_ms += ms_since(t0);
    cholmod_free_dense(&x, &f.c);
    link_count += static_cast<double>(last - first);
    ++t;
  }
  if (!f.ok()) state.SkipWithError("CHOLMOD failed while modifying the factor");
  // Independent check: the modified factor solves Λ assembled from scratch.
  const InformationMatrix blocks = assemble(links, n_states, t);
  const Eigen::SparseMatrix<double> lambda = blocks.to_sparse();
  cholmod_dense* x = cholmod_solve(CHOLMOD_A, f.L, &b, &f.c);
  const Eigen::Map<Eigen::MatrixXd> X(static_cast<double*>(x->x), rhs.rows(), rhs.cols());
  const double residual = (rhs - lambda * X).norm() / rhs.norm();
  cholmod_free_dense(&x, &f.c);
  if (!(residual <= 1e-8)) {
    state.SkipWithError(("modified factor's relative residual " + std::to_string(residual) +
                         " on Λ assembled from scratch")
                            .c_str());
  }
  // A refresh and its solve, each the second of two calls (the first allocates).
  (void)ExactMarginals::compute(lambda, kD);
  const ExactMarginals refresh = ExactMarginals::compute(lambda, kD);
  Eigen::MatrixXd z(rhs.rows(), rhs.cols());
  refresh.solve(rhs, z);
  const auto t0 = std::chrono::steady_clock::now();
  refresh.solve(rhs, z);
  const double steps = static_cast<double>(state.iterations());
  state.counters["supernodal_solve_ms"] = ms_since(t0);
  state.counters["block_jacobi_step_ms"] = block_jacobi_step_ms(blocks, rhs.col(0));
  state.counters["refresh_factor_ms"] = refresh.factor_ms();
  state.counters["refresh_inversion_ms"] = refresh.inversion_ms();
  state.counters["nnz_L_supernodal"] = static_cast<double>(refresh.factor_nnz());
  state.counters["nnz_L_modified"] = static_cast<double>(
      std::accumulate(static_cast<int*>(f.L->nz), static_cast<int*>(f.L->nz) + f.L->n, 0.0));
  state.counters["trailing_ms"] = trailing_ms / steps;
  state.counters["rowadd_ms"] = rowadd_ms / steps;
  state.counters["update_ms"] = update_ms / steps;
  state.counters["solve_ms"] = solve_ms / steps;
  state.counters["links"] = link_count / steps;
  state.counters["dim"] = static_cast<double>(lambda.rows());
}

BENCHMARK(BM_FactorKeptEqual)
    ->ArgNames({"states", "dense"})
    ->Args({1000, 0})
    ->Args({1000, 1})
    ->Args({10000, 0})
    ->Args({10000, 1})
    ->Args({100000, 0})
    ->Iterations(kAppended)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace nav::core
