// Pose-graph replay as a delayed-state filter with recovery and bounds (see posegraph/replay.h).
#include "nav/core/posegraph/replay.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "nav/core/geometry/pose.h"
#include "nav/core/models/binary_models.h"
#include "nav/core/recovery/bounds_renewal.h"
#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/markov_blanket.h"

namespace nav::core {
namespace {

std::string vertex_name(const PoseGraph& g, int index) {
  return "vertex " + std::to_string(g.vertices[static_cast<size_t>(index)].id) + " (index " +
         std::to_string(index) + ")";
}

std::string edge_name(const G2oEdge& e) {
  return "edge " + std::to_string(e.from) + "->" + std::to_string(e.to) + " (line " +
         std::to_string(e.line) + ")";
}

}  // namespace

Status ReplayOptions::validate() const {
  if (Status s = recovery.validate(); !s.ok()) return s;
  if (!(diffuse_process_variance > 0.0) || !std::isfinite(diffuse_process_variance)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "ReplayOptions.diffuse_process_variance must be finite and > 0");
  }
  Eigen::LLT<Mat6> llt(prior_covariance);
  if (!prior_covariance.allFinite() || llt.info() != Eigen::Success) {
    return Status::Error(StatusCode::kNotPositiveDefinite,
                         "ReplayOptions.prior_covariance must be symmetric positive definite");
  }
  return Status::Ok();
}

PoseGraphReplay::PoseGraphReplay(const PoseGraph& graph, ReplayOptions options)
    : graph_(graph),
      options_(options),
      filter_(kPoseDim),
      recovery_(kPoseDim, options.recovery),
      bounds_(kPoseDim, options.bounds) {}

Status PoseGraphReplay::start() {
  if (Status s = options_.validate(); !s.ok()) return s;
  const int n = num_vertices();
  if (n == 0) return Status::Error(StatusCode::kInvalidArgument, "pose graph has no vertices");
  plan_.assign(static_cast<size_t>(n), VertexPlan{});
  for (const G2oEdge& e : graph_.edges) {
    if (e.from_index == e.to_index) {
      return Status::Error(StatusCode::kInvalidArgument,
                           edge_name(e) + " joins a vertex to itself");
    }
    Eigen::LLT<Mat6> llt(e.information);
    if (!e.information.allFinite() || llt.info() != Eigen::Success) {
      return Status::Error(StatusCode::kNotPositiveDefinite,
                           edge_name(e) + ": information matrix is not positive definite");
    }
    const int k = std::max(e.from_index, e.to_index);
    plan_[static_cast<size_t>(k)].links.push_back(
        Link{&e, Mat6(llt.solve(Mat6::Identity()))});
  }
  broken_chain_ = 0;
  skipped_bound_updates_ = 0;
  for (int k = 1; k < n; ++k) {
    VertexPlan& p = plan_[static_cast<size_t>(k)];
    auto joins = [&](const Link& l, int a, int b) {
      return l.edge->from_index == a && l.edge->to_index == b;
    };
    auto it = std::find_if(p.links.begin(), p.links.end(),
                           [&](const Link& l) { return joins(l, k - 1, k); });
    if (it == p.links.end()) {
      it = std::find_if(p.links.begin(), p.links.end(),
                        [&](const Link& l) { return joins(l, k, k - 1); });
    }
    p.chain = it != p.links.end();
    if (!p.chain) {
      if (p.links.empty()) {
        return Status::Error(StatusCode::kInvalidArgument,
                             vertex_name(graph_, k) +
                                 " has no edge to an earlier vertex: no process model for it");
      }
      ++broken_chain_;
      p.process = p.links.front().edge;  // stays a link too (applied as an update)
    } else {
      p.process = it->edge;
      p.links.erase(it);
    }
  }
  const Vec6& x0 = graph_.vertices.front().pose;
  const Eigen::MatrixXd P0 = options_.prior_covariance;
  if (Status s = filter_.initialize(x0, P0); !s.ok()) return s;
  if (Status s = recovery_.initialize(x0, P0); !s.ok()) return s;
  if (Status s = bounds_.initialize_robot(P0); !s.ok()) return s;
  block_of_vertex_.assign(static_cast<size_t>(n), -1);
  block_of_vertex_[0] = Esdf::kRobotBlock;
  next_ = 1;
  current_ = -1;
  started_ = true;
  return Status::Ok();
}

int PoseGraphReplay::block_of_vertex(int vertex_index) const {
  if (vertex_index < 0 || static_cast<size_t>(vertex_index) >= block_of_vertex_.size()) return -1;
  return block_of_vertex_[static_cast<size_t>(vertex_index)];
}

int PoseGraphReplay::current_links() const {
  if (current_ < 0) return 0;
  return static_cast<int>(plan_[static_cast<size_t>(current_)].links.size());
}

Status PoseGraphReplay::process_model(int k, Eigen::MatrixXd* F, Eigen::MatrixXd* Q) const {
  const VertexPlan& p = plan_[static_cast<size_t>(k)];
  if (!p.chain) {
    *F = Eigen::MatrixXd::Zero(kPoseDim, kPoseDim);
    *Q = Eigen::MatrixXd::Identity(kPoseDim, kPoseDim) * options_.diffuse_process_variance;
    return Status::Ok();
  }
  const G2oEdge& e = *p.process;
  Mat6 R = e.information.llt().solve(Mat6::Identity());
  Vec6 z = e.measurement;
  if (e.from_index == k) {  // stored as (k -> k-1): invert to get x_{k-1,k}
    Mat6 J_inv;
    z = inverse_pose(e.measurement, &J_inv);
    R = J_inv * R * J_inv.transpose();
  }
  Mat6x12 J;
  try {
    head_to_tail(graph_.vertices[static_cast<size_t>(k - 1)].pose, z, &J);
  } catch (const std::exception& ex) {
    return Status::Error(StatusCode::kOutOfRange, edge_name(e) + ": " + ex.what());
  }
  *F = J.leftCols<6>();
  const Mat6 J_z = J.rightCols<6>();
  const Mat6 q = J_z * R * J_z.transpose();
  *Q = 0.5 * (q + q.transpose());
  return Status::Ok();
}

Status PoseGraphReplay::predict() {
  if (!started_ || done()) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "PoseGraphReplay::predict: not started or already done");
  }
  const int k = next_;
  Eigen::MatrixXd F, Q;
  if (Status s = process_model(k, &F, &Q); !s.ok()) return s;
  const Eigen::VectorXd f_of_mean = graph_.vertices[static_cast<size_t>(k)].pose;
  int kept = -1;
  if (Status s = filter_.predict(f_of_mean, F, Q, true, &kept); !s.ok()) {
    return Status::Error(s.code(), vertex_name(graph_, k) + ": " + s.message());
  }
  if (Status s = recovery_.extend_for_prediction(F, Q, f_of_mean, true, kept); !s.ok()) return s;
  if (Status s = bounds_.predict_robot(F, Q, true, kept); !s.ok()) return s;
  block_of_vertex_[static_cast<size_t>(k - 1)] = kept;
  block_of_vertex_[static_cast<size_t>(k)] = Esdf::kRobotBlock;
  current_ = k;
  return Status::Ok();
}

RecoveryResult PoseGraphReplay::recover() {
  RecoveryResult result;
  if (options_.recovery_operator == RecoveryOperator::kCsrSnapshot) {
    const CsrMatrix snapshot = filter_.information().to_sparse();
    result = recovery_.solve(snapshot, filter_.information_vector());
  } else {
    result = recovery_.solve(filter_.information(), filter_.information_vector());
  }
  if (!result.status.ok()) return result;
  result.status = renew_bounds(result, recovery_.refreshed_marginals(), filter_.num_blocks(),
                               bounds_, &renewal_snapshot_);
  if (!result.status.ok()) return result;
  std::function<OldStateEnergy()> old_states;  // K3 of the certificate, a solve: lazily
  if (bounds_.options().old_state_energy) old_states = [&] { return recovery_.old_state_energy(); };
  result.status = bounds_.set_recovery(recovery_.robot_covariance(), recovery_.column_residual(),
                                       filter_.num_blocks(), old_states);
  return result;
}

Status PoseGraphReplay::link_jacobians(const Link& link, MeasJac* H_a, MeasJac* H_b) const {
  const int a = block_of_vertex(link.edge->from_index);
  const int b = block_of_vertex(link.edge->to_index);
  try {
    RelativePose6Model{}.predict(filter_.mean_block(a), filter_.mean_block(b), H_a, H_b);
  } catch (const std::exception& ex) {
    return Status::Error(StatusCode::kOutOfRange, edge_name(*link.edge) + ": " + ex.what());
  }
  return Status::Ok();
}

Status PoseGraphReplay::update_bounds() {
  if (current_ < 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "PoseGraphReplay::update_bounds: call predict() first");
  }
  for (const Link& link : plan_[static_cast<size_t>(current_)].links) {
    const bool robot_is_from = link.edge->from_index == current_;
    const int other = robot_is_from ? link.edge->to_index : link.edge->from_index;
    const int i = block_of_vertex(other);
    MeasJac H_a, H_b;
    if (Status s = link_jacobians(link, &H_a, &H_b); !s.ok()) return s;
    LinkProposal proposal;
    if (Status s = bounds_.propose(i, recovery_.cross_covariance(i), &proposal); !s.ok()) {
      return s;
    }
    const Eigen::MatrixXd H_r = robot_is_from ? H_a : H_b;
    const Eigen::MatrixXd H_i = robot_is_from ? H_b : H_a;
    const Status s = bounds_.update(proposal, H_r, H_i, link.covariance);
    if (s.code() == StatusCode::kNotPositiveDefinite) {
      ++skipped_bound_updates_;
    } else if (!s.ok()) {
      return Status::Error(s.code(), edge_name(*link.edge) + ": " + s.message());
    }
  }
  return Status::Ok();
}

Status PoseGraphReplay::apply_links() {
  if (current_ < 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "PoseGraphReplay::apply_links: call predict() first");
  }
  const RelativePose6Model model;
  for (const Link& link : plan_[static_cast<size_t>(current_)].links) {
    const int a = block_of_vertex(link.edge->from_index);
    const int b = block_of_vertex(link.edge->to_index);
    const MeasVec z = link.edge->measurement;
    const MeasCov R = link.covariance;
    if (Status s = filter_.update(model, a, b, z, R); !s.ok()) {
      return Status::Error(s.code(), edge_name(*link.edge) + ": " + s.message());
    }
  }
  ++next_;
  current_ = -1;
  return Status::Ok();
}

Status PoseGraphReplay::step(RecoveryResult* result) {
  if (Status s = predict(); !s.ok()) return s;
  RecoveryResult r = recover();
  if (result != nullptr) *result = r;
  if (!r.status.ok()) return r.status;
  if (Status s = update_bounds(); !s.ok()) return s;
  return apply_links();
}

BoundsCheck check_bounds(const PoseGraphReplay& replay, const ExactMarginals& exact,
                         double tolerance, bool with_markov_blanket) {
  BoundsCheck check;
  check.worst_min_eigenvalue = 1e300;
  const CovarianceBounds& bounds = replay.bounds();
  const int blocks = replay.filter().num_blocks();
  auto check_one = [&](const Eigen::MatrixXd& bound, const Eigen::MatrixXd& sigma) {
    double min_eig = 0.0;
    ++check.checked;
    if (is_conservative(bound, sigma, tolerance, &min_eig)) ++check.conservative;
    check.worst_min_eigenvalue = std::min(check.worst_min_eigenvalue, min_eig);
  };
  check_one(bounds.robot_bound(), exact.marginal(Esdf::kRobotBlock));
  for (int i = 1; i < blocks; ++i) {
    if (!bounds.contains(i)) continue;
    const Eigen::MatrixXd sigma = exact.marginal(i);
    check_one(bounds.bound(i), sigma);
    try {
      check.logdet_ratio_ours.push_back(logdet_ratio(bounds.bound(i), sigma));
    } catch (const std::invalid_argument&) {
      ++check.not_positive_definite_bounds;  // only an uncertified, stale bound can be
    }
    if (with_markov_blanket) {
      const MarkovBlanketResult mb =
          markov_blanket_joint(replay.filter().information(), Esdf::kRobotBlock, i);
      const int d = replay.filter().block_dim();
      const Eigen::MatrixXd mb_ii = mb.joint.bottomRightCorner(d, d);
      check.logdet_ratio_markov_blanket.push_back(logdet_ratio(mb_ii, sigma));
      if (!is_conservative(mb_ii, sigma, tolerance)) ++check.markov_blanket_overconfident;
    }
  }
  return check;
}

}  // namespace nav::core
