// Civil UTC time <-> UNIX microseconds for the PD0/PD6 real-time clock fields.
// Day counting after H. Hinnant, "chrono-Compatible Low-Level Date Algorithms"
// (days_from_civil / civil_from_days, proleptic Gregorian calendar).
#include "civil_days.h"
#include "pd0_wire.h"

namespace nav::drivers::pd0_wire {
namespace {

using civil::days_from_civil;

bool is_leap(int y) { return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0; }

int days_in_month(int y, int m) {
  static constexpr int kDays[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return m == 2 && is_leap(y) ? 29 : kDays[m - 1];
}

}  // namespace

std::optional<int64_t> civil_to_unix_us(const CivilTime& t) {
  if (t.year < 1970 || t.year > 2255 || t.month < 1 || t.month > 12 || t.day < 1 ||
      t.day > days_in_month(t.year, t.month) || t.hour < 0 || t.hour > 23 || t.minute < 0 ||
      t.minute > 59 || t.second < 0 || t.second > 59 || t.hundredths < 0 || t.hundredths > 99) {
    return std::nullopt;
  }
  const int64_t days = days_from_civil(t.year, t.month, t.day);
  const int64_t seconds = days * 86400 + t.hour * 3600 + t.minute * 60 + t.second;
  return seconds * 1'000'000 + int64_t(t.hundredths) * 10'000;
}

CivilTime unix_us_to_civil(int64_t time_us) {
  int64_t seconds = time_us >= 0 ? time_us / 1'000'000 : (time_us - 999'999) / 1'000'000;
  const int64_t micros = time_us - seconds * 1'000'000;
  int64_t days = seconds >= 0 ? seconds / 86400 : (seconds - 86399) / 86400;
  const int64_t sod = seconds - days * 86400;
  // civil_from_days
  days += 719468;
  const int64_t era = (days >= 0 ? days : days - 146096) / 146097;
  const int64_t doe = days - era * 146097;
  const int64_t yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const int64_t doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const int64_t mp = (5 * doy + 2) / 153;
  CivilTime t;
  t.day = int(doy - (153 * mp + 2) / 5 + 1);
  t.month = int(mp < 10 ? mp + 3 : mp - 9);
  t.year = int(yoe + era * 400 + (t.month <= 2 ? 1 : 0));
  t.hour = int(sod / 3600);
  t.minute = int((sod % 3600) / 60);
  t.second = int(sod % 60);
  t.hundredths = int(micros / 10'000);
  return t;
}

}  // namespace nav::drivers::pd0_wire
