#pragma once
// Inputs of the covariance certificate (bounds.h): upper bounds of the residual energy
//   κ̄² = λmax(W^-½ Rᵀ Σ R W^-½)
// of a recovered covariance column X = Σ^_{*r} (n x d, block rows; R = E_r − ΛX the true
// residual, Σ = Λ⁻¹ never formed, W = B_rr >= Σ_rr, B_jj >= Σ_jj the stored bounds):
//   (K1) Rᵀ Σ R <= L RᵀR with L = Σ_j λmax(B_jj) >= λmax(Σ);
//   (K2) Rᵀ Σ R <= n Σ_j R_jᵀ B_jj R_j (D = blkdiag(B_jj): D^-½ Σ D^-½ has diagonal blocks
//        <= I, so λmax <= n);
//   (K3) with the factor of an earlier Λ₀ of the same filter (a refresh, factor_preconditioner.h)
//        whose blocks O = [1, k) are still blocks 1..k-1 of Λ: the filter's Λ has only gained
//        PSD terms since (bounds.h "Exact refresh"), so Σ_OO <= Σ₀_OO. With T = {0} ∪ [k, n)
//        (the robot and the states appended since, |T| blocks) and ω in (0, 1),
//        Σ <= blkdiag(Σ_OO / ω, Σ_TT / (1 − ω)) and Σ_TT <= |T| blkdiag(B_jj), hence
//          κ̄² <= a/ω + b/(1 − ω), minimal at ω = √a / (√a + √b): κ̄² <= (√a + √b)²,
//        a = λmax(W^-½ R_Oᵀ Σ₀_OO R_O W^-½) (OldStateEnergy, one forward solve with Λ₀'s
//        factor), b = |T| λmax(W^-½ Σ_{j in T} R_jᵀ B_jj R_j W^-½).
// K1 and K2 grow with the map (L and n); K3 = a (1 + √(b/a))² grows with |T| only and is
// close to R_Oᵀ Σ₀ R_O when the old states carry the residual. That keeps the certified joint
// tight where the relative-pose covariance is far smaller than the absolute one (long surveys,
// pose graphs with one gauge prior: docs/consistency.md "The certificate", "K3 and the floor
// at the time of use"). All three hold whatever the residual; the smallest is used.
#include <Eigen/Core>
#include <functional>

namespace nav::core {

/// The K3 input: `energy` >= R_Oᵀ Σ₀_OO R_O for the rows O = blocks [1, old_end) of the
/// residual (d x d); old_end = 0 means "no factor" (K1/K2 only). Valid only under the premise
/// above: Λ₀ was the same filter's Λ at a refresh, its blocks 1..old_end-1 are the same states.
struct OldStateEnergy {
  int old_end = 0;
  Eigen::MatrixXd energy;
};

/// (√a + √b)², the K3 bound from its two parts (a, b >= 0).
double kappa_squared_split(double a, double b);

/// λmax of a symmetric matrix (self-adjoint eigen-solve; for small blocks).
double lambda_max_symmetric(const Eigen::MatrixXd& m);
/// λmax(W^-½ G W^-½) for symmetric G and SPD W (generalised eigen-solve); +inf if it fails.
double lambda_max_scaled(const Eigen::MatrixXd& G, const Eigen::MatrixXd& W);

/// R_0ᵀ W R_0 + Σ_j R_jᵀ B_jj R_j over j in [max(first, 1), last), R_j the d x d block rows of
/// R (n x d, d = W's size), B_jj = bound(j): K2's sum (first = 0), K3's T part (first = k).
Eigen::MatrixXd weighted_block_gram(const Eigen::Ref<const Eigen::MatrixXd>& R, int first, int last,
                                    const Eigen::MatrixXd& W,
                                    const std::function<const Eigen::MatrixXd&(int)>& bound);

}  // namespace nav::core
