// Map (ESDF + Algorithm 1 bounds + warm start) to/from checkpoint sections
// (serialization/map_codec.h; the serialize functions: serialization/map_serialization.h).
#include "nav/core/serialization/map_codec.h"

#include <string>
#include <utility>

#include "nav/core/serialization/archive.h"
#include "nav/core/serialization/map_serialization.h"

namespace nav::core {
namespace {

/// A state recovery's warm start [μ | Σ_{*r}] both ways: u32 block_dim, u32 rows, u32 cols,
/// values. Reading requires the recovery's block_dim and at most `num_blocks` blocks (the warm
/// start may lag the filter, never lead it).
template <class Archive>
void serialize_warm_start(Archive& ar, int block_dim, int num_blocks, Eigen::MatrixXd& X) {
  auto dim = static_cast<std::uint32_t>(block_dim);
  ar(dim, "block_dim");
  if (!ar.check(dim == static_cast<std::uint32_t>(block_dim),
                "block_dim " + std::to_string(dim) + ", the recovery has " +
                    std::to_string(block_dim))) {
    return;
  }
  auto rows = static_cast<std::uint32_t>(X.rows());
  auto cols = static_cast<std::uint32_t>(X.cols());
  ar(rows, "warm start rows");
  ar(cols, "warm start columns");
  const auto d = static_cast<std::uint32_t>(block_dim);
  if (!ar.check(cols == d + 1 && rows % d == 0 &&
                    rows <= static_cast<std::uint64_t>(num_blocks) * std::uint64_t{d},
                "warm start is " + std::to_string(rows) + "x" + std::to_string(cols) +
                    ", expected at most " + std::to_string(num_blocks) + " blocks of " +
                    std::to_string(d) + " rows x " + std::to_string(d + 1))) {
    return;
  }
  if (!ar.check_count(std::uint64_t{rows} * cols, 8, "warm start")) return;
  if constexpr (Archive::kReading) X.resize(rows, cols);
  ar.values(X, "warm start");
}

}  // namespace


std::vector<std::uint8_t> encode_esdf(const Esdf& filter) {
  WriteArchive ar;
  const_cast<Esdf&>(filter).serialize(ar);  // writing only reads the fields
  return ar.take();
}

Status decode_esdf(std::span<const std::uint8_t> bytes, std::size_t base_offset,
                   std::optional<Esdf>* out) {
  ReadArchive ar(bytes, "ESDF section", base_offset);
  Esdf filter(1);
  filter.serialize(ar);
  if (Status s = ar.finish(); !s.ok()) return s;
  out->emplace(std::move(filter));
  return Status::Ok();
}

std::vector<std::uint8_t> encode_bounds(const CovarianceBounds& bounds) {
  WriteArchive ar;
  const_cast<CovarianceBounds&>(bounds).serialize(ar, 0);  // writing only reads the fields
  return ar.take();
}

Status decode_bounds(std::span<const std::uint8_t> bytes, std::size_t base_offset,
                     int num_filter_blocks, std::optional<CovarianceBounds>* out) {
  ReadArchive ar(bytes, "BNDS section", base_offset);
  CovarianceBounds bounds(1);
  bounds.serialize(ar, num_filter_blocks);
  if (Status s = ar.finish(); !s.ok()) return s;
  out->emplace(std::move(bounds));
  return Status::Ok();
}

Status add_map_sections(const Esdf& filter, const CovarianceBounds* bounds, SectionWriter* writer) {
  if (Status s = writer->add(kEsdfSectionTag, kEsdfSectionVersion, encode_esdf(filter)); !s.ok()) {
    return s;
  }
  if (bounds == nullptr) return Status::Ok();
  return writer->add(kBoundsSectionTag, kBoundsSectionVersion, encode_bounds(*bounds));
}

Status restore_map(const SectionSet& sections, std::optional<Esdf>* filter,
                   std::optional<CovarianceBounds>* bounds) {
  const SectionView* esdf_section = nullptr;
  if (Status s = sections.require(kEsdfSectionTag, kEsdfSectionVersion, &esdf_section); !s.ok()) {
    return s;
  }
  std::optional<Esdf> f;
  if (Status s = decode_esdf(esdf_section->bytes, esdf_section->offset, &f); !s.ok()) return s;
  std::optional<CovarianceBounds> b;
  if (bounds != nullptr) {
    const SectionView* v = nullptr;
    if (Status s = sections.require(kBoundsSectionTag, kBoundsSectionVersion, &v); !s.ok()) {
      return s;
    }
    if (Status s = decode_bounds(v->bytes, v->offset, f->num_blocks(), &b); !s.ok()) return s;
    if (b->block_dim() != f->block_dim()) {
      return Status::Error(StatusCode::kInvalidArgument, "map checkpoint: bounds have block_dim " +
                                                             std::to_string(b->block_dim()) +
                                                             ", the filter " +
                                                             std::to_string(f->block_dim()));
    }
  }
  filter->emplace(std::move(*f));
  if (bounds != nullptr) bounds->emplace(std::move(*b));
  return Status::Ok();
}

Status add_recovery_section(const StateRecovery& recovery, SectionWriter* writer) {
  WriteArchive ar;
  Eigen::MatrixXd X = recovery.solution();
  serialize_warm_start(ar, recovery.block_dim(), 0, X);
  return writer->add(kRecoverySectionTag, kRecoverySectionVersion, ar.take());
}

Status restore_recovery(const SectionSet& sections, int num_blocks, StateRecovery* recovery) {
  const SectionView* v = nullptr;
  if (Status s = sections.require(kRecoverySectionTag, kRecoverySectionVersion, &v); !s.ok()) {
    return s;
  }
  ReadArchive ar(v->bytes, "RCVY section", v->offset);
  Eigen::MatrixXd X;
  serialize_warm_start(ar, recovery->block_dim(), num_blocks, X);
  if (Status s = ar.finish(); !s.ok()) return s;
  if (X.rows() == 0) {  // an uninitialised filter: a recovery that has not started either
    *recovery = StateRecovery(recovery->block_dim(), recovery->options());
    return Status::Ok();
  }
  return recovery->set_solution(X);
}

}  // namespace nav::core
