// Map checkpoint serialisation (serialization/sections.h, map_codec.h): section container,
// bit-identical round trips of the ESDF and the Algorithm 1 bounds, a restored filter that
// continues bit-identically to the original, and rejection of every truncation and corruption.
#include "nav/core/serialization/map_codec.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "nav/core/serialization/byte_io.h"
#include "nav/core/serialization/sections.h"
#include "nav/core/sim/survey.h"

namespace nav::core {
namespace {

using Bytes = std::vector<std::uint8_t>;

bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

/// The simulated survey driving a filter, its state recovery and its bounds the way navd does:
/// predict (the recovery's warm start and the bounds follow with F, Q; a kept state gets the
/// robot's bound), unary updates, camera links; at each image a fixed-iteration PCG recovery
/// (the filter takes its mean, the bounds its Σ_rr and residual) and, for every link, the
/// Algorithm 1 update of the older image's bound.
StateRecoveryOptions recovery_options() {
  StateRecoveryOptions o;
  o.iterations_per_step = 30;  // enough for a good linearisation point on these small maps
  return o;
}

struct MapRun {
  explicit MapRun(const sim::Survey& s)
      : survey(&s), filter(12), bounds(12), recovery(12, recovery_options()) {
    EXPECT_TRUE(filter.initialize(s.x0_mean, s.P0).ok());
    EXPECT_TRUE(bounds.initialize_robot(s.P0).ok());
    EXPECT_TRUE(recovery.initialize(s.x0_mean, s.P0).ok());
  }

  void step(size_t k) {
    const sim::SurveyStep& st = survey->steps[k];
    Mat12 F, Q;
    const Vec12 f = sim::predicted_mean(*survey, st, filter.mean_block(Esdf::kRobotBlock), &F, &Q);
    const int blocks_before = filter.num_blocks();
    ASSERT_TRUE(sim::apply_step(*survey, st, filter, image_blocks).ok());
    const bool keep = st.image >= 0;
    const int kept = keep ? image_blocks.back() : -1;
    ASSERT_TRUE(bounds.predict_robot(F, Q, keep, kept).ok());
    ASSERT_TRUE(recovery.extend_for_prediction(F, Q, f, keep, keep ? blocks_before : -1).ok());
    if (!keep) return;
    const RecoveryResult r = recovery.solve(filter.information(), filter.information_vector());
    ASSERT_TRUE(r.status.ok()) << r.status.to_string();
    ASSERT_TRUE(filter.set_mean(recovery.mean()).ok());
    ASSERT_TRUE(bounds
                    .set_recovery(recovery.robot_covariance(), r.column_residual_frobenius,
                                  filter.num_blocks())
                    .ok());
    for (const sim::CameraLink& link : st.links) {
      const int a = image_blocks[static_cast<size_t>(link.image_a)];
      const int b = image_blocks[static_cast<size_t>(link.image_b)];
      MeasJac Ha, Hb;
      survey->camera.predict(filter.mean_block(a), filter.mean_block(b), &Ha, &Hb);
      LinkProposal p;
      ASSERT_TRUE(bounds.propose(a, recovery.cross_covariance(a), &p).ok());
      const Status s = bounds.update(p, Hb, Ha, survey->R_camera);
      ASSERT_TRUE(s.ok() || s.code() == StatusCode::kNotPositiveDefinite) << s.to_string();
    }
  }

  Bytes encode() const {
    SectionWriter w;
    EXPECT_TRUE(add_map_sections(filter, &bounds, &w).ok());
    EXPECT_TRUE(add_recovery_section(recovery, &w).ok());
    return w.finish();
  }

  const sim::Survey* survey;
  Esdf filter;
  CovarianceBounds bounds;
  StateRecovery recovery;
  std::vector<int> image_blocks;
};

sim::Survey small_survey(int images) {
  sim::SurveyOptions o;
  o.num_images = images;
  o.images_per_line = 4;
  o.link_radius_m = 3.0;
  o.min_cross_link_gap = 2;
  o.seed = 7;
  return sim::simulate_survey(o);
}

Status restore(const Bytes& payload, std::optional<Esdf>* f, std::optional<CovarianceBounds>* b,
               bool verify_crc = true) {
  SectionSet set;
  if (Status s = SectionSet::decode(payload, &set, SectionDecodeOptions{verify_crc}); !s.ok()) {
    return s;
  }
  return restore_map(set, f, b);
}

TEST(ByteReader, TruncationNamesFieldAndOffset) {
  ByteWriter w;
  w.u32(7);
  w.f64(1.5);
  const Bytes bytes = w.take();
  ByteReader r(std::span<const std::uint8_t>(bytes).first(9), "test payload", 100);
  std::uint32_t a = 0;
  double x = 0;
  ASSERT_TRUE(r.u32(&a, "count").ok());
  EXPECT_EQ(a, 7u);
  const Status s = r.f64(&x, "value");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("test payload: truncated reading value (needs 8 bytes, 5 left) at "
                             "offset 104"),
            std::string::npos)
      << s.message();
}

TEST(ByteReader, DoublesRoundTripAsBitsAndNonFiniteIsRefused) {
  ByteWriter w;
  w.f64(-0.0);
  w.f64(5e-324);
  w.f64(std::numeric_limits<double>::infinity());
  const Bytes bytes = w.take();
  EXPECT_EQ(bytes[7], 0x80);  // little-endian sign bit of -0.0
  ByteReader r(bytes, "p");
  double a = 1, b = 0, c = 0;
  ASSERT_TRUE(r.f64(&a, "a").ok());
  ASSERT_TRUE(r.f64(&b, "b").ok());
  EXPECT_TRUE(std::signbit(a));
  EXPECT_EQ(b, 5e-324);
  const Status s = r.f64(&c, "c");
  EXPECT_NE(s.message().find("c is not finite at offset 16"), std::string::npos) << s.message();
}

TEST(SectionContainer, RoundTripsTagsVersionsAndBytes) {
  SectionWriter w;
  const Bytes a = {1, 2, 3}, b = {};
  ASSERT_TRUE(w.add(section_tag("AAAA"), 3, a).ok());
  ASSERT_TRUE(w.add(section_tag("BBBB"), 1, b).ok());
  EXPECT_FALSE(w.add(section_tag("AAAA"), 1, b).ok());
  const Bytes bytes = w.finish();
  ASSERT_EQ(bytes.size(), kSectionContainerHeaderBytes + 2 * kSectionHeaderBytes + 3);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + 8), "NAVSECTS");
  SectionSet set;
  ASSERT_TRUE(SectionSet::decode(bytes, &set).ok());
  ASSERT_EQ(set.sections().size(), 2u);
  const SectionView* v = nullptr;
  ASSERT_TRUE(set.require(section_tag("AAAA"), 3, &v).ok());
  EXPECT_EQ(Bytes(v->bytes.begin(), v->bytes.end()), a);
  EXPECT_EQ(v->offset, kSectionContainerHeaderBytes + kSectionHeaderBytes);
  const Status wrong_version = set.require(section_tag("AAAA"), 4, &v);
  EXPECT_NE(wrong_version.message().find("section AAAA has version 3, this build reads 4"),
            std::string::npos);
  EXPECT_NE(set.require(section_tag("CCCC"), 1, &v).message().find("no CCCC section"),
            std::string::npos);
  EXPECT_EQ(section_tag_name(0x01020304u), "0x01020304");
}

TEST(SectionContainer, CrcMismatchNamesTheSection) {
  SectionWriter w;
  const Bytes a = {1, 2, 3};
  ASSERT_TRUE(w.add(section_tag("AAAA"), 1, a).ok());
  Bytes bytes = w.finish();
  bytes.back() ^= 0x10;
  SectionSet set;
  const Status s = SectionSet::decode(bytes, &set);
  EXPECT_NE(s.message().find("CRC-32 mismatch in section AAAA at offset 16"), std::string::npos)
      << s.message();
  EXPECT_TRUE(SectionSet::decode(bytes, &set, SectionDecodeOptions{false}).ok());
  bytes.push_back(0);
  EXPECT_NE(SectionSet::decode(bytes, &set, SectionDecodeOptions{false})
                .message()
                .find("1 unexpected trailing bytes"),
            std::string::npos);
}

TEST(MapCodec, RoundTripIsBitIdentical) {
  const sim::Survey survey = small_survey(12);
  MapRun run(survey);
  for (size_t k = 0; k < survey.steps.size(); ++k) ASSERT_NO_FATAL_FAILURE(run.step(k));
  ASSERT_GT(run.filter.information().num_off_diagonal_pairs(),
            static_cast<size_t>(run.filter.num_blocks()));  // loop closures present
  const Bytes payload = run.encode();
  std::optional<Esdf> f;
  std::optional<CovarianceBounds> b;
  ASSERT_TRUE(restore(payload, &f, &b).ok());
  EXPECT_EQ(f->num_blocks(), run.filter.num_blocks());
  EXPECT_TRUE(same_bits(f->information().to_dense(), run.filter.information().to_dense()));
  EXPECT_TRUE(same_bits(f->information_vector(), run.filter.information_vector()));
  EXPECT_TRUE(same_bits(f->mean(), run.filter.mean()));
  EXPECT_EQ(f->information().num_off_diagonal_pairs(),
            run.filter.information().num_off_diagonal_pairs());
  for (int i = 0; i < f->num_blocks(); ++i) {
    EXPECT_EQ(f->information().neighbours(i), run.filter.information().neighbours(i));
    if (i > 0) {
      EXPECT_TRUE(same_bits(b->bound(i), run.bounds.bound(i))) << i;
    }
  }
  EXPECT_EQ(b->num_bounds(), run.bounds.num_bounds());
  EXPECT_TRUE(same_bits(b->robot_bound(), run.bounds.robot_bound()));
  EXPECT_EQ(b->certificate_lambda(), run.bounds.certificate_lambda());
  EXPECT_EQ(b->lambda_max_sigma_bound(), run.bounds.lambda_max_sigma_bound());
  // Re-encoding the restored map and warm start gives the same bytes.
  SectionSet set;
  ASSERT_TRUE(SectionSet::decode(payload, &set).ok());
  StateRecovery recovery(12);
  ASSERT_TRUE(restore_recovery(set, f->num_blocks(), &recovery).ok());
  SectionWriter w;
  ASSERT_TRUE(add_map_sections(*f, &*b, &w).ok());
  ASSERT_TRUE(add_recovery_section(recovery, &w).ok());
  EXPECT_EQ(w.finish(), payload);
}

TEST(MapCodec, RestoredFilterContinuesBitIdentically) {
  const sim::Survey survey = small_survey(16);
  const size_t n = survey.steps.size();
  for (size_t cut : {size_t{1}, n / 3, n / 2 + 1, n - 2}) {
    MapRun original(survey);
    for (size_t k = 0; k < cut; ++k) ASSERT_NO_FATAL_FAILURE(original.step(k));
    const Bytes checkpoint = original.encode();

    MapRun resumed(survey);
    std::optional<Esdf> f;
    std::optional<CovarianceBounds> b;
    ASSERT_TRUE(restore(checkpoint, &f, &b).ok());
    resumed.filter = std::move(*f);
    resumed.bounds = std::move(*b);
    SectionSet set;
    ASSERT_TRUE(SectionSet::decode(checkpoint, &set).ok());
    ASSERT_TRUE(restore_recovery(set, resumed.filter.num_blocks(), &resumed.recovery).ok());
    resumed.image_blocks = original.image_blocks;  // the daemon keeps this in its own section

    for (size_t k = cut; k < n; ++k) {
      ASSERT_NO_FATAL_FAILURE(original.step(k));
      ASSERT_NO_FATAL_FAILURE(resumed.step(k));
    }
    EXPECT_EQ(resumed.encode(), original.encode()) << "cut at step " << cut;
    EXPECT_TRUE(same_bits(resumed.filter.mean(), original.filter.mean()));
    EXPECT_TRUE(same_bits(resumed.recovery.solution(), original.recovery.solution()));
  }
}

TEST(MapCodec, EveryTruncationAndFlippedByteIsRejectedWithTheCrc) {
  const sim::Survey survey = small_survey(2);  // 3 blocks, ~18 kB: every byte, quickly
  MapRun run(survey);
  for (size_t k = 0; k < survey.steps.size(); ++k) ASSERT_NO_FATAL_FAILURE(run.step(k));
  const Bytes payload = run.encode();
  std::optional<Esdf> f;
  std::optional<CovarianceBounds> b;
  for (size_t len = 0; len < payload.size(); ++len) {
    const Bytes cut(payload.begin(), payload.begin() + static_cast<std::ptrdiff_t>(len));
    ASSERT_FALSE(restore(cut, &f, &b).ok()) << "truncated to " << len;
  }
  for (size_t i = 0; i < payload.size(); ++i) {
    // Every byte flipped once: a single bit at even offsets, all eight at odd ones (the ASan
    // run stays short; the CRC catches any error burst up to 32 bits).
    const std::uint8_t mask = i % 2 == 0 ? 0x01 : 0xFF;
    Bytes bad = payload;
    bad[i] ^= mask;
    ASSERT_FALSE(restore(bad, &f, &b).ok()) << "byte " << i << " ^ " << int{mask};
  }
  EXPECT_FALSE(f.has_value());  // never a half-built filter
  EXPECT_FALSE(b.has_value());
}

/// Without the CRC, decoding alone must refuse every inconsistent size: a corrupted section is
/// either rejected or decodes to a map whose encoding is exactly the corrupted bytes (a value
/// changed, nothing read past an end or misaligned). Under ASan this also proves no bad read.
template <class Decode>
void check_section_without_crc(const Bytes& section, Decode decode, const char* name) {
  for (size_t len = 0; len < section.size(); ++len) {
    const Bytes cut(section.begin(), section.begin() + static_cast<std::ptrdiff_t>(len));
    ASSERT_FALSE(decode(cut).ok()) << name << " truncated to " << len;
  }
  int accepted = 0;
  for (size_t i = 0; i < section.size(); ++i) {
    for (std::uint8_t mask : {std::uint8_t{0x01}, std::uint8_t{0x80}, std::uint8_t{0xFF}}) {
      Bytes bad = section;
      bad[i] ^= mask;
      Bytes re_encoded;
      const Status s = decode(bad, &re_encoded);
      if (s.ok()) {
        ++accepted;
        ASSERT_EQ(re_encoded, bad) << name << " byte " << i << " ^ " << int{mask};
      }
    }
  }
  // Most flips land in values (accepted as other values); the structure bytes are refused.
  EXPECT_GT(accepted, 0) << name;
}

TEST(MapCodec, DecodeWithoutCrcRefusesInconsistentSizes) {
  const sim::Survey survey = small_survey(2);
  MapRun run(survey);
  for (size_t k = 0; k < survey.steps.size(); ++k) ASSERT_NO_FATAL_FAILURE(run.step(k));
  const Bytes esdf = encode_esdf(run.filter);
  const Bytes bounds = encode_bounds(run.bounds);
  const int n = run.filter.num_blocks();
  check_section_without_crc(
      esdf,
      [](const Bytes& bytes, Bytes* re = nullptr) {
        std::optional<Esdf> f;
        Status s = decode_esdf(bytes, 0, &f);
        if (s.ok() && re != nullptr) *re = encode_esdf(*f);
        EXPECT_EQ(s.ok(), f.has_value());
        return s;
      },
      "ESDF");
  check_section_without_crc(
      bounds,
      [n](const Bytes& bytes, Bytes* re = nullptr) {
        std::optional<CovarianceBounds> b;
        Status s = decode_bounds(bytes, 0, n, &b);
        if (s.ok() && re != nullptr) *re = encode_bounds(*b);
        EXPECT_EQ(s.ok(), b.has_value());
        return s;
      },
      "BNDS");
  // And the whole container with the CRC off: every truncation is still refused.
  const Bytes payload = run.encode();
  std::optional<Esdf> f;
  std::optional<CovarianceBounds> b;
  for (size_t len = 0; len < payload.size(); ++len) {
    const Bytes cut(payload.begin(), payload.begin() + static_cast<std::ptrdiff_t>(len));
    ASSERT_FALSE(restore(cut, &f, &b, false).ok()) << "truncated to " << len;
  }
}

TEST(MapCodec, ErrorsSayWhatAndWhere) {
  const sim::Survey survey = small_survey(3);
  MapRun run(survey);
  for (size_t k = 0; k < survey.steps.size(); ++k) ASSERT_NO_FATAL_FAILURE(run.step(k));
  Bytes esdf = encode_esdf(run.filter);
  std::optional<Esdf> f;
  // Row 0's neighbour count sits after d, n, the counter and the 12x12 diagonal block.
  const size_t count_at = 4 + 4 + 8 + 8 * 144;
  Bytes bad = esdf;
  bad[count_at] = 0xEE;
  Status s = decode_esdf(bad, 1000, &f);
  EXPECT_NE(s.message().find("ESDF section: neighbour count 238 cannot fit"), std::string::npos)
      << s.message();
  EXPECT_NE(s.message().find("at offset " + std::to_string(1000 + count_at + 4)), std::string::npos)
      << s.message();
  // Break the transpose of the first off-diagonal block of row 0.
  bad = esdf;
  bad[count_at + 4 + 4 + 8 * 1 + 3] ^= 0x40;  // entry (1, 0) of Λ_{0,j}
  s = decode_esdf(bad, 0, &f);
  EXPECT_NE(s.message().find("has no exact transpose"), std::string::npos) << s.message();
  EXPECT_FALSE(f.has_value());

  // Bounds of a bigger map do not fit a smaller filter.
  std::optional<CovarianceBounds> b;
  s = decode_bounds(encode_bounds(run.bounds), 0, 2, &b);
  EXPECT_NE(s.message().find("is not a delayed state of the 2-block filter"), std::string::npos)
      << s.message();
  // A 6-element filter with 12-element bounds.
  Esdf other(6);
  ASSERT_TRUE(other.initialize(Vec6::Zero(), Mat6::Identity()).ok());
  for (int k = 0; k < 5; ++k) {
    ASSERT_TRUE(other.predict(Vec6::Zero(), Mat6::Identity(), Mat6::Identity(), true).ok());
  }
  SectionWriter w;
  ASSERT_TRUE(add_map_sections(other, &run.bounds, &w).ok());
  SectionSet set;
  const Bytes mixed = w.finish();
  ASSERT_TRUE(SectionSet::decode(mixed, &set).ok());
  s = restore_map(set, &f, &b);
  EXPECT_NE(s.message().find("bounds have block_dim 12, the filter 6"), std::string::npos)
      << s.message();
  EXPECT_FALSE(f.has_value());
  EXPECT_FALSE(b.has_value());
}

TEST(MapCodec, RecoveryWarmStartMustFitTheFilter) {
  const sim::Survey survey = small_survey(3);
  MapRun run(survey);
  for (size_t k = 0; k < survey.steps.size(); ++k) ASSERT_NO_FATAL_FAILURE(run.step(k));
  SectionWriter w;
  ASSERT_TRUE(add_recovery_section(run.recovery, &w).ok());
  const Bytes bytes = w.finish();
  SectionSet set;
  ASSERT_TRUE(SectionSet::decode(bytes, &set).ok());
  StateRecovery other(12);
  ASSERT_TRUE(other.initialize(survey.x0_mean, survey.P0).ok());
  const Eigen::MatrixXd before = other.solution();
  const int n = run.filter.num_blocks();
  const Status s = restore_recovery(set, n - 1, &other);  // a warm start ahead of the filter
  EXPECT_NE(s.message().find("RCVY section: warm start is " + std::to_string(12 * n) +
                             "x13, expected at most " + std::to_string(n - 1) + " blocks"),
            std::string::npos)
      << s.message();
  EXPECT_TRUE(same_bits(other.solution(), before));  // unchanged on error
  ASSERT_TRUE(restore_recovery(set, n, &other).ok());
  EXPECT_TRUE(same_bits(other.solution(), run.recovery.solution()));
}

}  // namespace
}  // namespace nav::core
