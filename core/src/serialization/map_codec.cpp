// Map (ESDF + Algorithm 1 bounds) to/from checkpoint sections (see serialization/map_codec.h).
#include "nav/core/serialization/map_codec.h"

#include <string>
#include <utility>

#include "nav/core/serialization/byte_io.h"

namespace nav::core {

/// Reaches into the private state of the map classes (friend of each); only this file uses it.
struct MapCodecAccess {
  using Block = InformationMatrix::Block;

  static void write_matrix_rows(const InformationMatrix& info, ByteWriter& w);
  static Status read_matrix_rows(ByteReader& r, InformationMatrix* info);
  static Status check_symmetry(InformationMatrix& info, const ByteReader& r);
  static void write_vector(const BlockVector& v, ByteWriter& w);
  static Status read_vector(ByteReader& r, int num_blocks, BlockVector* v, const char* field);

  static std::vector<std::uint8_t> encode(const Esdf& filter);
  static Status decode(ByteReader& r, std::optional<Esdf>* out);
  static std::vector<std::uint8_t> encode(const CovarianceBounds& bounds);
  static Status decode(ByteReader& r, int num_filter_blocks, std::optional<CovarianceBounds>* out);
  static Status read_bound_entry(ByteReader& r, const CovarianceBounds& b, int previous_state,
                                 int num_filter_blocks, int* state, CovarianceBounds::Entry* e);
};

// ---- ESDF ---------------------------------------------------------------------------------

void MapCodecAccess::write_matrix_rows(const InformationMatrix& info, ByteWriter& w) {
  for (const InformationMatrix::Row& row : info.rows_) {
    w.values(row.diagonal);
    w.u32(static_cast<std::uint32_t>(row.off.size()));
    for (const InformationMatrix::Entry& e : row.off) {
      w.u32(static_cast<std::uint32_t>(e.col));
      w.values(e.block);
    }
  }
}

Status MapCodecAccess::read_matrix_rows(ByteReader& r, InformationMatrix* info) {
  const int d = info->block_dim_;
  const int n = static_cast<int>(info->rows_.size());
  const std::size_t block_bytes = 8 * static_cast<std::size_t>(d) * static_cast<std::size_t>(d);
  for (int i = 0; i < n; ++i) {
    InformationMatrix::Row& row = info->rows_[static_cast<std::size_t>(i)];
    row.diagonal.resize(d, d);
    if (Status s = r.values(&row.diagonal, "diagonal block"); !s.ok()) return s;
    std::uint32_t k = 0;
    if (Status s = r.u32(&k, "neighbour count"); !s.ok()) return s;
    if (Status s = r.check_count(k, 4 + block_bytes, "neighbour count"); !s.ok()) return s;
    if (k >= static_cast<std::uint32_t>(n)) {
      return r.error("row " + std::to_string(i) + " has " + std::to_string(k) +
                     " neighbours but the filter has " + std::to_string(n) + " blocks");
    }
    row.off.resize(k);
    for (InformationMatrix::Entry& e : row.off) {
      std::uint32_t col = 0;
      if (Status s = r.u32(&col, "neighbour column"); !s.ok()) return s;
      if (col >= static_cast<std::uint32_t>(n) || col == static_cast<std::uint32_t>(i)) {
        return r.error("row " + std::to_string(i) + " neighbour column " + std::to_string(col) +
                       " is not another block of " + std::to_string(n));
      }
      for (const InformationMatrix::Entry& prev : row.off) {
        if (&prev == &e) break;
        if (prev.col == static_cast<int>(col)) {
          return r.error("row " + std::to_string(i) + " lists neighbour " + std::to_string(col) +
                         " twice");
        }
      }
      e.col = static_cast<int>(col);
      e.block.resize(d, d);
      if (Status s = r.values(&e.block, "off-diagonal block"); !s.ok()) return s;
    }
  }
  return Status::Ok();
}

Status MapCodecAccess::check_symmetry(InformationMatrix& info, const ByteReader& r) {
  std::size_t halves = 0;
  for (int i = 0; i < info.num_blocks(); ++i) {
    const InformationMatrix::Row& row = info.rows_[static_cast<std::size_t>(i)];
    if (row.diagonal != row.diagonal.transpose()) {
      return r.error("diagonal block " + std::to_string(i) + " is not symmetric");
    }
    for (const InformationMatrix::Entry& e : row.off) {
      const Block* mirror = info.find_block(e.col, i);
      if (mirror == nullptr || *mirror != e.block.transpose()) {
        return r.error("block (" + std::to_string(i) + ", " + std::to_string(e.col) +
                       ") has no exact transpose at (" + std::to_string(e.col) + ", " +
                       std::to_string(i) + ")");
      }
      ++halves;
    }
  }
  // Every half has its mirror and no row lists a column twice, so halves is even.
  info.num_pairs_ = halves / 2;
  return Status::Ok();
}

void MapCodecAccess::write_vector(const BlockVector& v, ByteWriter& w) {
  for (const BlockVector::Segment& s : v.blocks_) w.values(s);
}

Status MapCodecAccess::read_vector(ByteReader& r, int num_blocks, BlockVector* v,
                                   const char* field) {
  if (Status s = r.check_count(
          static_cast<std::uint64_t>(num_blocks) * static_cast<std::uint64_t>(v->block_dim_), 8,
          field);
      !s.ok()) {
    return s;
  }
  for (int i = 0; i < num_blocks; ++i) {
    BlockVector::Segment& seg = v->blocks_.emplace_back(v->block_dim_);
    if (Status s = r.values(&seg, field); !s.ok()) return s;
  }
  v->changed_.clear();
  v->all_changed_ = true;
  return Status::Ok();
}

std::vector<std::uint8_t> MapCodecAccess::encode(const Esdf& filter) {
  ByteWriter w;
  w.u32(static_cast<std::uint32_t>(filter.block_dim()));
  w.u32(static_cast<std::uint32_t>(filter.num_blocks()));
  w.u64(filter.info_.blocks_written_);
  write_matrix_rows(filter.info_, w);
  write_vector(filter.eta_, w);
  write_vector(filter.mean_, w);
  return w.take();
}

Status MapCodecAccess::decode(ByteReader& r, std::optional<Esdf>* out) {
  std::uint32_t d = 0, n = 0;
  std::uint64_t written = 0;
  if (Status s = r.u32(&d, "block_dim"); !s.ok()) return s;
  if (d < 1 || d > static_cast<std::uint32_t>(InformationMatrix::kMaxBlockDim)) {
    return r.error("block_dim " + std::to_string(d) + " outside [1, 12]");
  }
  if (Status s = r.u32(&n, "block count"); !s.ok()) return s;
  // A row is at least its diagonal block and its neighbour count; η and μ add 2 d doubles.
  const std::size_t min_row_bytes = 8 * d * d + 4 + 16 * d;
  if (Status s = r.check_count(n, min_row_bytes, "block count"); !s.ok()) return s;
  if (Status s = r.u64(&written, "blocks-written counter"); !s.ok()) return s;
  Esdf filter(static_cast<int>(d));
  filter.info_.rows_.resize(n);
  filter.info_.blocks_written_ = written;
  if (Status s = read_matrix_rows(r, &filter.info_); !s.ok()) return s;
  if (Status s = check_symmetry(filter.info_, r); !s.ok()) return s;
  if (Status s = read_vector(r, static_cast<int>(n), &filter.eta_, "information vector η");
      !s.ok()) {
    return s;
  }
  if (Status s = read_vector(r, static_cast<int>(n), &filter.mean_, "mean μ"); !s.ok()) return s;
  if (Status s = r.expect_end(); !s.ok()) return s;
  out->emplace(std::move(filter));
  return Status::Ok();
}

// ---- Bounds -------------------------------------------------------------------------------

std::vector<std::uint8_t> MapCodecAccess::encode(const CovarianceBounds& b) {
  ByteWriter w;
  w.u32(static_cast<std::uint32_t>(b.block_dim_));
  w.u8(b.options_.certify_truncation ? 1 : 0);
  w.matrix(b.robot_bound_);
  w.f64(b.robot_lambda_max_);
  w.matrix(b.sigma_rr_hat_);
  w.f64(b.residual_frobenius_);
  w.f64(b.epsilon_robot_);
  w.f64(b.certificate_lambda_);
  w.f64(b.lambda_sum_);
  w.i64(b.epoch_);
  w.u32(static_cast<std::uint32_t>(b.num_bounds_));
  for (std::size_t state = 0; state < b.entries_.size(); ++state) {
    const CovarianceBounds::Entry& e = b.entries_[state];
    if (!e.present) continue;
    w.u32(static_cast<std::uint32_t>(state));
    w.matrix(e.bound);
    w.f64(e.lambda_max);
    w.matrix(e.snapshot_bound);
    w.f64(e.snapshot_lambda_max);
    w.i64(e.snapshot_epoch);
  }
  return w.take();
}

Status MapCodecAccess::read_bound_entry(ByteReader& r, const CovarianceBounds& b,
                                        int previous_state, int num_filter_blocks, int* state,
                                        CovarianceBounds::Entry* e) {
  const int d = b.block_dim_;
  std::uint32_t s32 = 0;
  if (Status s = r.u32(&s32, "bound state"); !s.ok()) return s;
  // States are written ascending and must be delayed states of the filter (1..n-1), which
  // also keeps a corrupt index from sizing the table.
  if (s32 < 1 || static_cast<std::int64_t>(s32) <= previous_state ||
      static_cast<std::int64_t>(s32) >= num_filter_blocks) {
    return r.error("bound state " + std::to_string(s32) + " is not a delayed state of the " +
                   std::to_string(num_filter_blocks) + "-block filter after state " +
                   std::to_string(previous_state));
  }
  *state = static_cast<int>(s32);
  e->present = true;
  if (Status s = r.matrix(&e->bound, d, d, false, "state bound"); !s.ok()) return s;
  if (Status s = r.f64(&e->lambda_max, "state bound λmax"); !s.ok()) return s;
  if (Status s = r.matrix(&e->snapshot_bound, d, d, true, "snapshot bound"); !s.ok()) return s;
  if (Status s = r.f64(&e->snapshot_lambda_max, "snapshot λmax"); !s.ok()) return s;
  std::int64_t epoch = 0;
  if (Status s = r.i64(&epoch, "snapshot epoch"); !s.ok()) return s;
  if (epoch < -1 || epoch > b.epoch_ || (epoch == -1) != (e->snapshot_bound.size() == 0)) {
    return r.error("snapshot epoch " + std::to_string(epoch) + " of state " + std::to_string(s32) +
                   " does not match its snapshot bound (" +
                   std::to_string(e->snapshot_bound.rows()) + " rows) and the epoch " +
                   std::to_string(b.epoch_));
  }
  e->snapshot_epoch = epoch;
  return Status::Ok();
}

Status MapCodecAccess::decode(ByteReader& r, int num_filter_blocks,
                              std::optional<CovarianceBounds>* out) {
  std::uint32_t d = 0;
  std::uint8_t certify = 0;
  if (Status s = r.u32(&d, "bounds block_dim"); !s.ok()) return s;
  if (d < 1 || d > static_cast<std::uint32_t>(InformationMatrix::kMaxBlockDim)) {
    return r.error("bounds block_dim " + std::to_string(d) + " outside [1, 12]");
  }
  if (Status s = r.u8(&certify, "certify_truncation"); !s.ok()) return s;
  if (certify > 1)
    return r.error("certify_truncation byte " + std::to_string(certify) + " not 0/1");
  CovarianceBounds b(static_cast<int>(d), BoundsOptions{certify == 1});
  const auto di = static_cast<Eigen::Index>(d);
  if (Status s = r.matrix(&b.robot_bound_, di, di, true, "robot bound"); !s.ok()) return s;
  if (Status s = r.f64(&b.robot_lambda_max_, "robot bound λmax"); !s.ok()) return s;
  if (Status s = r.matrix(&b.sigma_rr_hat_, di, di, true, "recovered Σ_rr"); !s.ok()) return s;
  if (Status s = r.f64(&b.residual_frobenius_, "residual"); !s.ok()) return s;
  if (b.residual_frobenius_ < 0) return r.error("negative recovery residual");
  if (Status s = r.f64(&b.epsilon_robot_, "ε_r"); !s.ok()) return s;
  if (Status s = r.f64(&b.certificate_lambda_, "certificate L"); !s.ok()) return s;
  if (Status s = r.f64(&b.lambda_sum_, "Σ λmax"); !s.ok()) return s;
  std::int64_t epoch = 0;
  if (Status s = r.i64(&epoch, "epoch"); !s.ok()) return s;
  if (epoch < 0) return r.error("negative epoch " + std::to_string(epoch));
  b.epoch_ = epoch;
  std::uint32_t m = 0;
  if (Status s = r.u32(&m, "bound count"); !s.ok()) return s;
  // state, bound (shape + d*d), λmax, snapshot bound (at least its 0x0 shape), λmax, epoch
  const std::size_t min_entry_bytes = 4 + (8 + 8 * d * d) + 8 + 8 + 8 + 8;
  if (Status s = r.check_count(m, min_entry_bytes, "bound count"); !s.ok()) return s;
  int previous = 0;
  for (std::uint32_t k = 0; k < m; ++k) {
    CovarianceBounds::Entry e;
    int state = 0;
    if (Status s = read_bound_entry(r, b, previous, num_filter_blocks, &state, &e); !s.ok()) {
      return s;
    }
    b.entries_.resize(static_cast<std::size_t>(state) + 1);
    b.entries_[static_cast<std::size_t>(state)] = std::move(e);
    previous = state;
  }
  b.num_bounds_ = static_cast<int>(m);
  if (Status s = r.expect_end(); !s.ok()) return s;
  out->emplace(std::move(b));
  return Status::Ok();
}

// ---- public functions ---------------------------------------------------------------------

std::vector<std::uint8_t> encode_esdf(const Esdf& filter) { return MapCodecAccess::encode(filter); }

Status decode_esdf(std::span<const std::uint8_t> bytes, std::size_t base_offset,
                   std::optional<Esdf>* out) {
  ByteReader r(bytes, "ESDF section", base_offset);
  return MapCodecAccess::decode(r, out);
}

std::vector<std::uint8_t> encode_bounds(const CovarianceBounds& bounds) {
  return MapCodecAccess::encode(bounds);
}

Status decode_bounds(std::span<const std::uint8_t> bytes, std::size_t base_offset,
                     int num_filter_blocks, std::optional<CovarianceBounds>* out) {
  ByteReader r(bytes, "BNDS section", base_offset);
  return MapCodecAccess::decode(r, num_filter_blocks, out);
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
  ByteWriter w;
  w.u32(static_cast<std::uint32_t>(recovery.block_dim()));
  w.matrix(recovery.solution());
  return writer->add(kRecoverySectionTag, kRecoverySectionVersion, w.data());
}

Status restore_recovery(const SectionSet& sections, int num_blocks, StateRecovery* recovery) {
  const SectionView* v = nullptr;
  if (Status s = sections.require(kRecoverySectionTag, kRecoverySectionVersion, &v); !s.ok()) {
    return s;
  }
  ByteReader r(v->bytes, "RCVY section", v->offset);
  const int d = recovery->block_dim();
  std::uint32_t dim = 0;
  if (Status s = r.u32(&dim, "block_dim"); !s.ok()) return s;
  if (dim != static_cast<std::uint32_t>(d)) {
    return r.error("block_dim " + std::to_string(dim) + ", the recovery has " + std::to_string(d));
  }
  // The warm start may lag the filter (NavFilter extends it once per image), never lead it.
  const std::size_t at = r.offset();
  std::uint32_t rows = 0, cols = 0;
  if (Status s = r.u32(&rows, "warm start rows"); !s.ok()) return s;
  if (Status s = r.u32(&cols, "warm start columns"); !s.ok()) return s;
  if (cols != static_cast<std::uint32_t>(d + 1) || rows % static_cast<std::uint32_t>(d) != 0 ||
      rows > static_cast<std::uint64_t>(num_blocks) * static_cast<std::uint64_t>(d)) {
    return Status::Error(
        StatusCode::kInvalidArgument,
        "RCVY section: warm start is " + std::to_string(rows) + "x" + std::to_string(cols) +
            ", expected at most " + std::to_string(num_blocks) + " blocks of " + std::to_string(d) +
            " rows x " + std::to_string(d + 1) + " at offset " + std::to_string(at));
  }
  if (Status s = r.check_count(std::uint64_t{rows} * cols, 8, "warm start"); !s.ok()) return s;
  Eigen::MatrixXd X(rows, cols);
  if (Status s = r.values(&X, "warm start"); !s.ok()) return s;
  if (Status s = r.expect_end(); !s.ok()) return s;
  if (X.rows() == 0) {  // an uninitialised filter: a recovery that has not started either
    *recovery = StateRecovery(d, recovery->options());
    return Status::Ok();
  }
  return recovery->set_solution(X);
}

}  // namespace nav::core
