#pragma once
// Internal helper of the codecs that read calendar time stamps (PD0/PD6 real-time clock,
// candump -t A logs): day counting in the proleptic Gregorian calendar after H. Hinnant,
// "chrono-Compatible Low-Level Date Algorithms" (days_from_civil).
#include <cstdint>

namespace nav::drivers::civil {

/// Days since 1970-01-01 of the date y-m-d (month 1..12, day 1..31; negative before 1970).
constexpr int64_t days_from_civil(int64_t y, int64_t m, int64_t d) {
  y -= m <= 2 ? 1 : 0;
  const int64_t era = (y >= 0 ? y : y - 399) / 400;
  const int64_t yoe = y - era * 400;
  const int64_t doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const int64_t doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + doe - 719468;
}

static_assert(days_from_civil(1970, 1, 1) == 0);
static_assert(days_from_civil(2000, 3, 1) == 11017);

}  // namespace nav::drivers::civil
