#pragma once
// Serialisation of the map for checkpoints: the ESDF (Λ, η, μ) and the
// Algorithm 1 covariance bounds, as sections of the container of sections.h. Restoring gives
// back objects whose every later operation is bit-identical to the original's: all doubles are
// stored as their bit patterns and Λ's block rows keep their storage order (the order in which
// predict and PCG visit neighbours, hence the rounding of every later sum).
//
// Section "ESDF", version 1 (d = block_dim, n = number of blocks):
//   u32 d, u32 n, u64 blocks-written counter,
//   n x { d*d diagonal block, u32 k, k x { u32 column, d*d block } }   (both halves stored)
//   n*d η, n*d μ
// Section "BNDS", version 3 (v2 had no growth; v1 had the isotropic ε_r instead of κ and W):
//   u32 d, u8 certify_truncation, matrix robot bound (d x d or 0 x 0 before initialize_robot),
//   f64 λmax(robot bound), matrix Σ^_rr (d x d or 0 x 0), f64 residual ‖R‖_F, f64 κ,
//   matrix W (certificate robot bound, d x d or 0 x 0), f64 certificate L, f64 running Σ λmax,
//   i64 epoch, f64 rounding growth since set_recovery (log), u32 m,
//   m x { u32 state, matrix bound (d x d), f64 λmax, matrix snapshot bound (d x d, or 0 x 0 when
//         never snapshotted), f64 snapshot λmax, i64 snapshot epoch }   (states ascending)
// Section "RCVY", version 1: the state recovery's warm start [μ | Σ_{*r}] (the only state a
//   StateRecovery carries between solves; its preconditioner is refactored every solve):
//   u32 d, matrix (n*d) x (1 + d).
// (matrix = u32 rows, u32 cols, values; values = doubles column-major, little-endian.)
// Each layout is written and read by ONE serialize function per type (map_serialization.h,
// archive.h), so encoder and decoder cannot disagree.
//
// Decoding checks every size against the bytes present before allocating, every index range,
// that the two stored halves of Λ are exact transposes and the diagonal blocks exactly
// symmetric, that every value is finite, and that the bounds belong to states of the filter;
// errors name the field and its offset. On error the outputs are untouched: never a half-built
// filter.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "nav/core/filter/esdf.h"
#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/state_recovery.h"
#include "nav/core/serialization/sections.h"
#include "nav/core/status.h"

namespace nav::core {

inline constexpr std::uint32_t kEsdfSectionTag = section_tag("ESDF");
inline constexpr std::uint32_t kEsdfSectionVersion = 1;
inline constexpr std::uint32_t kBoundsSectionTag = section_tag("BNDS");
inline constexpr std::uint32_t kBoundsSectionVersion = 3;
inline constexpr std::uint32_t kRecoverySectionTag = section_tag("RCVY");
inline constexpr std::uint32_t kRecoverySectionVersion = 1;

/// The "ESDF" section's bytes.
std::vector<std::uint8_t> encode_esdf(const Esdf& filter);
/// Parses an "ESDF" section; base_offset = the section's offset in the container (errors).
Status decode_esdf(std::span<const std::uint8_t> bytes, std::size_t base_offset,
                   std::optional<Esdf>* out);

/// The "BNDS" section's bytes.
std::vector<std::uint8_t> encode_bounds(const CovarianceBounds& bounds);
/// Parses a "BNDS" section; every bound must belong to a delayed state 1..num_filter_blocks-1.
Status decode_bounds(std::span<const std::uint8_t> bytes, std::size_t base_offset,
                     int num_filter_blocks, std::optional<CovarianceBounds>* out);

/// Adds the "ESDF" section and, when bounds != nullptr, the "BNDS" section.
Status add_map_sections(const Esdf& filter, const CovarianceBounds* bounds, SectionWriter* writer);

/// Restores the filter (required) and, when `bounds` != nullptr, the bounds (required then).
/// Cross-checks: same block_dim, every bound belongs to a delayed state of the filter
/// (1 <= state < num_blocks). Both outputs are written only when everything decoded.
Status restore_map(const SectionSet& sections, std::optional<Esdf>* filter,
                   std::optional<CovarianceBounds>* bounds);

/// Adds the "RCVY" section (the warm start of `recovery`).
Status add_recovery_section(const StateRecovery& recovery, SectionWriter* writer);
/// Sets recovery's warm start from the "RCVY" section; it may have at most `num_blocks` blocks
/// of the recovery's block_dim (it may lag the filter, never lead it). On error `recovery` is
/// unchanged.
Status restore_recovery(const SectionSet& sections, int num_blocks, StateRecovery* recovery);

}  // namespace nav::core
