// Exactly sparse delayed-state filter: prediction (augment + marginalise), EIF updates and
// direct mean recovery. Eustice, Singh & Leonard, ICRA 2005; Eustice et al., RSS 2005 eqs. 1-3.
#include "nav/core/filter/esdf.h"

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <cmath>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>

namespace nav::core {
namespace {

using Block = InformationMatrix::Block;
using Segment = BlockVector::Segment;
using BlockByMeas = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 12,
                                  kMaxMeasDim>;

// `where` is a const char* throughout: building a std::string on the success path would
// allocate (names longer than the small-string buffer) in the real-time predict/update.
Status invalid(const char* where, const std::string& what) {
  return Status::Error(StatusCode::kInvalidArgument, std::string(where) + ": " + what);
}

/// Position (row, col) of the first non-finite entry, or (-1, -1). 2-D indexing, so it is
/// correct for Eigen::Ref views with any outer stride.
template <class M>
std::pair<Eigen::Index, Eigen::Index> first_non_finite(const M& m) {
  for (Eigen::Index c = 0; c < m.cols(); ++c) {
    for (Eigen::Index r = 0; r < m.rows(); ++r) {
      if (!std::isfinite(m(r, c))) return {r, c};
    }
  }
  return {-1, -1};
}

template <class M>
M symmetric(const M& m) {
  return 0.5 * (m + m.transpose());
}

/// The robot's terms of a marginalising prediction (the comment above Esdf::predict).
struct RobotMarginalisation {
  Block lambda_rr;          ///< S⁻¹
  Block gain;               ///< A Ω⁻¹ = S⁻¹ F Σ_c
  Segment eta_r;            ///< S⁻¹ (F Σ_c η_t + c)
  Eigen::LLT<Block> omega;  ///< Ω = Λ_tt + FᵀQ⁻¹F, for the neighbours' terms
  Segment omega_inv_b;      ///< Ω⁻¹ (η_t − FᵀQ⁻¹ c)
};

/// The terms from the old robot's block L_tt and vector eta_t (Qi = Q⁻¹), in D x D fixed-size
/// arithmetic (Eigen::Dynamic: any block size); nullptr on success, else the matrix that is not
/// positive definite.
template <int D>
const char* marginalise_robot(const Block& L_tt, const Segment& eta_t, const Block& F_block,
                              const Block& Q, const Block& Qi, const Segment& c_block,
                              RobotMarginalisation& out) {
  using M = std::conditional_t<D == Eigen::Dynamic, Block, Eigen::Matrix<double, D, D>>;
  using V = std::conditional_t<D == Eigen::Dynamic, Segment, Eigen::Matrix<double, D, 1>>;
  const M F = F_block;
  const V c = c_block, eta = eta_t;
  const M identity = M::Identity(L_tt.rows(), L_tt.cols());
  const Eigen::LLT<M> t_llt{M(L_tt)};
  if (t_llt.info() != Eigen::Success) return "robot block information Λ_tt";
  const M F_sigma = F * symmetric(M(t_llt.solve(identity)));  // F Σ_c
  const Eigen::LLT<M> s_llt(symmetric(M(M(Q) + F_sigma * F.transpose())));
  if (s_llt.info() != Eigen::Success) return "Q + F Λ_tt⁻¹ Fᵀ";
  out.lambda_rr = symmetric(M(s_llt.solve(identity)));
  out.gain = M(s_llt.solve(F_sigma));
  out.eta_r = V(s_llt.solve(V(F_sigma * eta + c)));
  const M A = M(Qi) * F;
  out.omega.compute(Block(M(M(L_tt) + F.transpose() * A)));
  if (out.omega.info() != Eigen::Success) return "robot block information Λ_tt + FᵀQ⁻¹F";
  out.omega_inv_b = out.omega.solve(Segment(V(eta - A.transpose() * c)));
  return nullptr;
}

const char* marginalise_robot(const Block& L_tt, const Segment& eta_t, const Block& F,
                              const Block& Q, const Block& Qi, const Segment& c,
                              RobotMarginalisation& out) {
  switch (L_tt.rows()) {
    case 12:
      return marginalise_robot<12>(L_tt, eta_t, F, Q, Qi, c, out);
    case 6:
      return marginalise_robot<6>(L_tt, eta_t, F, Q, Qi, c, out);
    default:
      return marginalise_robot<Eigen::Dynamic>(L_tt, eta_t, F, Q, Qi, c, out);
  }
}

template <class M>
Status check_finite(const M& m, const char* where, const char* name) {
  const auto [r, c] = first_non_finite(m);
  if (r < 0) return Status::Ok();
  std::ostringstream os;
  os << name << " has a non-finite entry (" << m(r, c) << " at row " << r << ", column " << c
     << ")";
  return invalid(where, os.str());
}

template <class M>
Status check_shape(const M& m, Eigen::Index rows, Eigen::Index cols, const char* where,
                   const char* name) {
  if (m.rows() == rows && m.cols() == cols) return Status::Ok();
  std::ostringstream os;
  os << name << " is " << m.rows() << "x" << m.cols() << ", expected " << rows << "x" << cols;
  return invalid(where, os.str());
}

/// Symmetric (to 1e-9 relative) and positive definite (LLT succeeds).
template <class M, class Llt>
Status check_spd(const M& m, const char* where, const char* name, Llt* llt) {
  const double scale = std::max(1.0, m.cwiseAbs().maxCoeff());
  if ((m - m.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
    return Status::Error(StatusCode::kNotPositiveDefinite,
                         std::string(where) + ": " + name + " is not symmetric");
  }
  llt->compute(m);
  if (llt->info() != Eigen::Success) {
    return Status::Error(StatusCode::kNotPositiveDefinite,
                         std::string(where) + ": " + name +
                             " is not positive definite (Cholesky failed)");
  }
  return Status::Ok();
}

}  // namespace

namespace detail {
Status model_error(const char* where, const std::exception& e) {
  StatusCode code = StatusCode::kNumericalFailure;
  if (dynamic_cast<const std::domain_error*>(&e) != nullptr) code = StatusCode::kOutOfRange;
  if (dynamic_cast<const std::invalid_argument*>(&e) != nullptr) {
    code = StatusCode::kInvalidArgument;
  }
  return Status::Error(code, std::string(where) + ": measurement/process model: " + e.what());
}
}  // namespace detail

Esdf::Esdf(int block_dim) : info_(block_dim), eta_(block_dim), mean_(block_dim) {}

void Esdf::begin_stats() {
  stats_ = UpdateStats{};
  blocks_written_at_start_ = info_.blocks_written();
}

void Esdf::end_stats() {
  stats_.blocks_written = static_cast<int>(info_.blocks_written() - blocks_written_at_start_);
}

Status Esdf::check_block(int block, const char* where) const {
  if (block >= 0 && block < num_blocks()) return Status::Ok();
  return Status::Error(StatusCode::kUnknownState,
                       std::string(where) + ": block " + std::to_string(block) +
                           " is not in the filter (" + std::to_string(num_blocks()) +
                           " blocks)");
}

Status Esdf::initialize(const Eigen::VectorXd& x0, const Eigen::MatrixXd& P0) {
  const char* where = "Esdf::initialize";
  const int d = block_dim();
  if (Status s = check_shape(x0, d, 1, where, "x0"); !s.ok()) return s;
  if (Status s = check_shape(P0, d, d, where, "P0"); !s.ok()) return s;
  if (Status s = check_finite(x0, where, "x0"); !s.ok()) return s;
  if (Status s = check_finite(P0, where, "P0"); !s.ok()) return s;
  Eigen::LLT<Eigen::MatrixXd> llt;
  if (Status s = check_spd(P0, where, "P0", &llt); !s.ok()) return s;
  Eigen::MatrixXd L0 = llt.solve(Eigen::MatrixXd::Identity(d, d));
  L0 = 0.5 * (L0 + L0.transpose()).eval();

  begin_stats();
  info_ = InformationMatrix(d);
  eta_.clear();
  mean_.clear();
  info_.add_block();
  eta_.append();
  mean_.append();
  info_.add_to_block(kRobotBlock, kRobotBlock, L0);
  eta_.mutable_segment(kRobotBlock) = L0 * x0;
  mean_.mutable_segment(kRobotBlock) = x0;
  stats_.segments_written = 2;
  end_stats();
  return Status::Ok();
}

// Prediction (ESDF, ICRA 2005 section III-A; RSS 2005 eq. 1-2). With c = f(μ_t) − F μ_t the
// linearised process is x_{t+1} = F x_t + c + w, w ~ N(0, Q). Write A = Q⁻¹F.
// Augmenting x_{t+1} to [x_t, M] (M = delayed states) gives
//   Λ_{t+1,t+1} = Q⁻¹,  Λ_{t+1,t} = −A,  Λ_{t,t} += Fᵀ A,  (Λ_{t+1,M} = 0)
//   η_{t+1} = Q⁻¹ c,    η_t −= Aᵀ c.
// keep_current: that is the result; x_t is moved to a new block index k, x_{t+1} is block 0.
// Otherwise x_t is marginalised by the Schur complement. With Ω = Λ_tt + FᵀA (after
// augmentation: Λ_tt is the old robot block) and b = η_t − Aᵀc:
//   Λ_{t+1,t+1} = Q⁻¹ − A Ω⁻¹ Aᵀ
//   Λ_{t+1,j}   = A Ω⁻¹ Λ_tj                     for every neighbour j of x_t
//   Λ_{jl}     −= Λ_jt Ω⁻¹ Λ_tl                  for neighbours j, l of x_t
//   η_{t+1}     = Q⁻¹ c + A Ω⁻¹ b,   η_j −= Λ_jt Ω⁻¹ b.
// Computed so, a step of a few milliseconds (Q⁻¹ ~ dt⁻³ ~ 1e10) forms the robot's block and
// vector as differences of terms about 1e6 times larger than the result, and loses those
// digits at every step (docs/consistency.md "The dead-reckoning baseline"). So the robot's
// terms are computed in their Woodbury forms, with the robot's conditional covariance
// Σ_c = Λ_tt⁻¹ (before augmentation) and S = Q + F Σ_c Fᵀ (push-through identity
// (Λ + FᵀQ⁻¹F)⁻¹ FᵀQ⁻¹ = Λ⁻¹ Fᵀ (Q + F Λ⁻¹ Fᵀ)⁻¹):
//   Λ_{t+1,t+1} = S⁻¹,   A Ω⁻¹ = S⁻¹ F Σ_c,   η_{t+1} = S⁻¹ (F Σ_c η_t + c),
// sums of positive semi-definite terms and products. The neighbours' terms keep Ω: Ω⁻¹ is
// small where Q is, and its Woodbury form Σ_c − Σ_c Fᵀ S⁻¹ F Σ_c would leave an error of the
// size of Σ_c in it.
// Only x_t's neighbours are touched. In the delayed-state chain x_t's only neighbour is the
// newest delayed state (camera links join delayed states), so the fill-in is exactly the
// robot–newest pair (ICRA 2005, Fig. 2). The mean of x_{t+1} is f(μ_t).
Status Esdf::predict(const Eigen::Ref<const Eigen::VectorXd>& f_of_mean,
                     const Eigen::Ref<const Eigen::MatrixXd>& F,
                     const Eigen::Ref<const Eigen::MatrixXd>& Q, bool keep_current,
                     int* kept_block) {
  const char* where = "Esdf::predict";
  if (!initialized()) {
    return Status::Error(StatusCode::kUnknownState, std::string(where) + ": filter not initialised");
  }
  const int d = block_dim();
  if (Status s = check_shape(f_of_mean, d, 1, where, "f(mean)"); !s.ok()) return s;
  if (Status s = check_shape(F, d, d, where, "F"); !s.ok()) return s;
  if (Status s = check_shape(Q, d, d, where, "Q"); !s.ok()) return s;
  if (Status s = check_finite(f_of_mean, where, "f(mean)"); !s.ok()) return s;
  if (Status s = check_finite(F, where, "F"); !s.ok()) return s;
  if (Status s = check_finite(Q, where, "Q"); !s.ok()) return s;
  Eigen::LLT<Block> q_llt(d);
  const Block Qb = Q;
  if (Status s = check_spd(Qb, where, "Q", &q_llt); !s.ok()) return s;

  const Block Qi = symmetric(Block(q_llt.solve(Block::Identity(d, d))));
  const Block Fb = F;
  const Segment mu_t = mean_.segment(kRobotBlock);
  const Segment f = f_of_mean;
  const Segment c = f - Fb * mu_t;

  if (keep_current) {
    const Block A = Qi * Fb;
    const Block FtA = Fb.transpose() * A;
    begin_stats();
    const int k = info_.add_block();
    eta_.append();
    mean_.append();
    info_.swap_rows(kRobotBlock, k);
    eta_.swap_blocks(kRobotBlock, k);
    mean_.swap_blocks(kRobotBlock, k);
    info_.add_to_block(k, k, FtA);
    info_.add_to_block(kRobotBlock, kRobotBlock, Qi);
    info_.add_to_block(kRobotBlock, k, -A);
    eta_.mutable_segment(k) -= A.transpose() * c;
    eta_.mutable_segment(kRobotBlock) = Qi * c;
    mean_.mutable_segment(kRobotBlock) = f;
    stats_.segments_written = 6;
    end_stats();
    if (kept_block != nullptr) *kept_block = k;
    return Status::Ok();
  }

  // Marginalise x_t. Everything that can fail is computed before the first write.
  RobotMarginalisation m;
  if (const char* not_pd = marginalise_robot(info_.diagonal_block(kRobotBlock),
                                             eta_.segment(kRobotBlock), Fb, Qb, Qi, c, m)) {
    return Status::Error(
        StatusCode::kNumericalFailure,
        std::string(where) + ": " + not_pd + " is not positive definite; cannot marginalise");
  }
  const int n_nbrs = info_.num_neighbours(kRobotBlock);
  scratch_nbrs_.resize(static_cast<size_t>(n_nbrs));
  scratch_lambda_tj_.resize(static_cast<size_t>(n_nbrs));
  scratch_w_.resize(static_cast<size_t>(n_nbrs));
  for (int k = 0; k < n_nbrs; ++k) {
    const auto ks = static_cast<size_t>(k);
    scratch_nbrs_[ks] = info_.neighbour(kRobotBlock, k);
    scratch_lambda_tj_[ks] = info_.neighbour_block(kRobotBlock, k);
    scratch_w_[ks] = m.omega.solve(scratch_lambda_tj_[ks]);  // Ω⁻¹ Λ_tj
  }

  begin_stats();
  info_.clear_row(kRobotBlock);
  info_.add_to_block(kRobotBlock, kRobotBlock, m.lambda_rr);
  eta_.mutable_segment(kRobotBlock) = m.eta_r;
  for (int k = 0; k < n_nbrs; ++k) {
    const auto ks = static_cast<size_t>(k);
    const int j = scratch_nbrs_[ks];
    const Block& L_tj = scratch_lambda_tj_[ks];
    info_.add_to_block(kRobotBlock, j, Block(m.gain * L_tj));
    eta_.mutable_segment(j) -= L_tj.transpose() * m.omega_inv_b;
    for (int l = k; l < n_nbrs; ++l) {
      const auto ls = static_cast<size_t>(l);
      info_.add_to_block(j, scratch_nbrs_[ls], Block(-(L_tj.transpose() * scratch_w_[ls])));
    }
  }
  mean_.mutable_segment(kRobotBlock) = f;
  stats_.segments_written = 2 + n_nbrs;
  stats_.neighbours = n_nbrs;
  end_stats();
  if (kept_block != nullptr) *kept_block = -1;
  return Status::Ok();
}

Status Esdf::predict(const ConstantVelocityModel& model, double dt_s, bool keep_current,
                     int* kept_block) {
  const char* where = "Esdf::predict(model)";
  if (!initialized()) {
    return Status::Error(StatusCode::kUnknownState, std::string(where) + ": not initialised");
  }
  if (block_dim() != kRobotDim) {
    return invalid(where, "the constant-velocity model needs 12-element blocks, filter has " +
                              std::to_string(block_dim()));
  }
  const Vec12 x = mean_.segment(kRobotBlock);
  Mat12 F;
  Vec12 f;
  Mat12 Q;
  try {
    f = model.predict(x, dt_s, &F);
    Q = model.process_noise(x, dt_s);
  } catch (const std::exception& e) {
    return detail::model_error(where, e);
  }
  return predict(f, F, Q, keep_current, kept_block);
}

Status Esdf::check_measurement(const MeasVec& z, const MeasVec& h, const MeasJac* H1,
                               const MeasJac* H2, const MeasCov& R, const char* where,
                               Eigen::LLT<MeasCov>* llt) const {
  const char* w = where;
  const Eigen::Index m = z.size();
  if (m < 1 || m > kMaxMeasDim) {
    return invalid(w, "z has " + std::to_string(m) + " rows, expected 1..6");
  }
  if (Status s = check_shape(h, m, 1, w, "h(mean)"); !s.ok()) return s;
  if (Status s = check_shape(R, m, m, w, "R"); !s.ok()) return s;
  for (const MeasJac* H : {H1, H2}) {
    if (H == nullptr) continue;
    if (Status s = check_shape(*H, m, block_dim(), w, "H"); !s.ok()) return s;
    if (Status s = check_finite(*H, w, "H"); !s.ok()) return s;
  }
  if (Status s = check_finite(z, w, "z"); !s.ok()) return s;
  if (Status s = check_finite(h, w, "h(mean)"); !s.ok()) return s;
  if (Status s = check_finite(R, w, "R"); !s.ok()) return s;
  return check_spd(R, w, "R", llt);
}

Status Esdf::update(int block, const MeasVec& z, const MeasVec& h_at_mean, const MeasJac& H,
                    const MeasCov& R, const AngleMask& angle_rows) {
  const char* where = "Esdf::update";
  if (Status s = check_block(block, where); !s.ok()) return s;
  Eigen::LLT<MeasCov> llt;
  if (Status s = check_measurement(z, h_at_mean, &H, nullptr, R, where, &llt); !s.ok()) return s;
  const auto m = z.size();
  MeasVec nu = z - h_at_mean;
  for (Eigen::Index r = 0; r < m; ++r) {
    if (angle_rows[static_cast<int>(r)]) nu[r] = wrap_angle(nu[r]);
  }
  // Hᵀ R⁻¹ = (R⁻¹ H)ᵀ
  const BlockByMeas HtRi = llt.solve(H).transpose();
  const MeasVec y = nu + H * mean_.segment(block);

  begin_stats();
  info_.add_to_block(block, block, Block(HtRi * H));
  eta_.mutable_segment(block) += HtRi * y;
  stats_.segments_written = 1;
  end_stats();
  return Status::Ok();
}

Status Esdf::update(int a, int b, const MeasVec& z, const MeasVec& h_at_mean, const MeasJac& H_a,
                    const MeasJac& H_b, const MeasCov& R, const AngleMask& angle_rows) {
  const char* where = "Esdf::update(a, b)";
  if (Status s = check_block(a, where); !s.ok()) return s;
  if (Status s = check_block(b, where); !s.ok()) return s;
  if (a == b) {
    return invalid(where, "binary update needs two different blocks, got " + std::to_string(a) +
                              " twice");
  }
  Eigen::LLT<MeasCov> llt;
  if (Status s = check_measurement(z, h_at_mean, &H_a, &H_b, R, where, &llt); !s.ok()) return s;
  const auto m = z.size();
  MeasVec nu = z - h_at_mean;
  for (Eigen::Index r = 0; r < m; ++r) {
    if (angle_rows[static_cast<int>(r)]) nu[r] = wrap_angle(nu[r]);
  }
  const BlockByMeas HaRi = llt.solve(H_a).transpose();
  const BlockByMeas HbRi = llt.solve(H_b).transpose();
  const MeasVec y = nu + H_a * mean_.segment(a) + H_b * mean_.segment(b);

  begin_stats();
  info_.add_to_block(a, a, Block(HaRi * H_a));
  info_.add_to_block(a, b, Block(HaRi * H_b));
  info_.add_to_block(b, b, Block(HbRi * H_b));
  eta_.mutable_segment(a) += HaRi * y;
  eta_.mutable_segment(b) += HbRi * y;
  stats_.segments_written = 2;
  end_stats();
  return Status::Ok();
}

Status Esdf::set_mean(const Eigen::VectorXd& mean) {
  const char* where = "Esdf::set_mean";
  if (mean.size() != info_.dim()) {
    return invalid(where, "mean has " + std::to_string(mean.size()) + " elements, filter has " +
                              std::to_string(info_.dim()));
  }
  if (Status s = check_finite(mean, where, "mean"); !s.ok()) return s;
  mean_.assign(mean);
  return Status::Ok();
}

Status Esdf::set_mean_block(int block, const Eigen::Ref<const Eigen::VectorXd>& mean) {
  const char* where = "Esdf::set_mean_block";
  if (Status s = check_block(block, where); !s.ok()) return s;
  if (mean.size() != block_dim()) {
    return invalid(where, "block mean has " + std::to_string(mean.size()) + " elements, blocks have " +
                              std::to_string(block_dim()));
  }
  if (!mean.allFinite()) return invalid(where, "block mean is not finite");
  mean_.mutable_segment(block) = mean;
  return Status::Ok();
}

Status Esdf::recover_mean_direct() {
  const char* where = "Esdf::recover_mean_direct";
  if (!initialized()) {
    return Status::Error(StatusCode::kUnknownState, std::string(where) + ": filter not initialised");
  }
  const Eigen::SparseMatrix<double> L = info_.to_sparse();
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> chol(L);
  if (chol.info() != Eigen::Success) {
    return Status::Error(StatusCode::kNumericalFailure,
                         std::string(where) + ": CHOLMOD factorisation of Λ failed (not positive definite?)");
  }
  const Eigen::VectorXd mu = chol.solve(eta_.dense());
  if (chol.info() != Eigen::Success || first_non_finite(mu).first >= 0) {
    return Status::Error(StatusCode::kNumericalFailure,
                         std::string(where) + ": CHOLMOD solve produced a non-finite mean");
  }
  mean_.assign(mu);
  return Status::Ok();
}

}  // namespace nav::core
