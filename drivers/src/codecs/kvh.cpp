// KVH DSP-3000 ASCII output decoder and encoder (see kvh.h).
#include "nav/drivers/codecs/kvh.h"

#include <cmath>
#include <numbers>

#include "ascii_text.h"

namespace nav::drivers {
namespace {

double to_rad(double value, KvhAngleUnit unit) {
  return unit == KvhAngleUnit::kDegrees ? value * std::numbers::pi / 180.0 : value;
}

double from_rad(double value, KvhAngleUnit unit) {
  return unit == KvhAngleUnit::kDegrees ? value * 180.0 / std::numbers::pi : value;
}

}  // namespace

std::string KvhOptions::validate() const {
  if (!(max_rate_radps > 0.0 && std::isfinite(max_rate_radps))) {
    return "KvhOptions.max_rate_radps must be > 0";
  }
  if (!(max_integrated_angle_rad > 0.0 && std::isfinite(max_integrated_angle_rad))) {
    return "KvhOptions.max_integrated_angle_rad must be > 0";
  }
  if (max_line_chars < 8 || max_line_chars > 256) {
    return "KvhOptions.max_line_chars=" + std::to_string(max_line_chars) + " outside [8, 256]";
  }
  return {};
}

struct KvhDecoder::Impl {
  explicit Impl(KvhOptions o) : options(o), framer(o.max_line_chars) {}

  bool on_line(std::string_view line, const HostTime& received, std::vector<KvhRecord>& out) {
    // "<value><whitespace><status>", leading/trailing blanks allowed.
    const std::string_view text = ascii::trim(line);
    const std::size_t gap = text.find_first_of(" \t");
    if (gap == std::string_view::npos) {
      ++stats.malformed;
      return false;
    }
    const auto value = ascii::parse_decimal(text.substr(0, gap));
    const std::string_view status = ascii::trim(text.substr(gap));
    if (!value || (status != "0" && status != "1")) {
      ++stats.malformed;
      return false;
    }
    KvhRecord record;
    record.time = Timestamps{received, std::nullopt};
    record.mode = options.mode;
    record.sensor_valid = status == "1";
    if (record.sensor_valid) {
      const double v = to_rad(*value, options.unit);
      const double limit = options.mode == KvhOutputMode::kIntegratedAngle
                               ? options.max_integrated_angle_rad
                               : options.max_rate_radps;
      if (std::abs(v) > limit) {
        ++stats.out_of_range;
        return false;
      }
      if (options.mode == KvhOutputMode::kRate) {
        record.rate_radps = v;
      } else {
        record.angle_rad = v;
      }
    }
    out.push_back(record);
    ++stats.records;
    return true;
  }

  KvhOptions options;
  ascii::LineFramer framer;
  DecodeStats stats;
};

KvhDecoder::KvhDecoder(KvhOptions options) : impl_(std::make_unique<Impl>(options)) {}
KvhDecoder::~KvhDecoder() = default;
KvhDecoder::KvhDecoder(KvhDecoder&&) noexcept = default;
KvhDecoder& KvhDecoder::operator=(KvhDecoder&&) noexcept = default;

void KvhDecoder::feed(std::span<const uint8_t> bytes, const HostTime& received,
                      std::vector<KvhRecord>& out) {
  Impl& impl = *impl_;
  impl.stats.bytes += bytes.size();
  impl.framer.feed(bytes, impl.stats,
                   [&](std::string_view line) { return impl.on_line(line, received, out); });
}

const DecodeStats& KvhDecoder::stats() const { return impl_->stats; }

std::string encode_kvh(const KvhRecord& record, const KvhOptions& options) {
  const std::optional<double>& value =
      options.mode == KvhOutputMode::kRate ? record.rate_radps : record.angle_rad;
  const bool valid = record.sensor_valid && value.has_value();
  std::string text = ascii::format_fixed(valid ? from_rad(*value, options.unit) : 0.0, 7);
  if (text.size() < 13) text.insert(0, 13 - text.size(), ' ');
  return text + (valid ? "   1\r\n" : "   0\r\n");
}

}  // namespace nav::drivers
