// Writes the seed inputs of the daemon's fuzz targets (no binary seed is committed):
// * <dir>/checkpoint: the checkpoint payloads (nav_filter_payload, as navd writes them) of a
//   NavFilter on config/sim.yaml after the first 3 s, 6 s and 10 s of a synthetic dive
//   (tests/support/synthetic_dive.h: DVL, attitude, depth, altitude, an image every 2 s and
//   their registrations): delayed states, bounds, links and a resume point;
// * <dir>/registration: LCM-encoded registration_t of that dive, one signed, one with a NaN
//   covariance and one with an indefinite one.
// Usage: fuzz_seeds <directory>.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "../tests/support/synthetic_dive.h"
#include "nav/daemon/filter/registration_signature.h"
#include "nav/daemon/checkpoint/nav_filter_checkpointer.h"
#include "nav/daemon/checkpoint/resume_point.h"

namespace {

void write(const std::filesystem::path& file, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

void write_registrations(const nav::testing::SyntheticDive& dive, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::vector<navlcm::registration_t> seeds(dive.registration_messages.begin(),
                                            dive.registration_messages.begin() + 3);
  seeds[0].run_id = 0x0123'4567'89ab'cdef;
  seeds[0].sequence = 1;
  nav::daemon::sign_registration(
      seeds[0], nav::daemon::signing_key_from_hex("000102030405060708090a0b0c0d0e0f"), 1,
      seeds[0].utime);
  seeds[1].covariance[6] = std::nan("");
  seeds[2].covariance[12] = -1.0;
  for (std::size_t k = 0; k < seeds.size(); ++k) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(seeds[k].getEncodedSize()));
    seeds[k].encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    write(dir / ("registration_" + std::to_string(k)), bytes);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <directory>\n", argv[0]);
    return 2;
  }
  const std::filesystem::path dir = std::filesystem::path(argv[1]) / "checkpoint";
  std::filesystem::create_directories(dir);
  const nav::daemon::NavdConfig config =
      nav::testing::synthetic_dive_config(NAV_SOURCE_DIR "/config/sim.yaml");
  nav::testing::SyntheticDiveOptions o;
  o.duration_s = 10.0;
  const nav::testing::SyntheticDive dive = nav::testing::make_synthetic_dive(config, o);
  write_registrations(dive, std::filesystem::path(argv[1]) / "registration");
  nav::daemon::NavFilter filter(nav::daemon::filter_options_from_config(config),
                                &dive.registrations);
  nav::daemon::AppliedTracker tracker;
  const double stops_s[] = {3.0, 6.0, 10.0};
  std::size_t next = 0;
  for (const double stop_s : stops_s) {
    while (next < dive.measurements.size() &&
           nav::daemon::validity_us(dive.measurements[next]) - dive.truth_origin_us <=
               static_cast<std::int64_t>(stop_s * 1e6)) {
      if (!filter.process(dive.measurements[next]).ok()) {
        std::fprintf(stderr, "fuzz_seeds: filter failed at measurement %zu\n", next);
        return 1;
      }
      tracker.applied(dive.measurements[next++]);
    }
    const std::vector<std::uint8_t> payload =
        nav::daemon::nav_filter_payload(filter, tracker.point(), "seed");
    const std::filesystem::path file = dir / ("payload_" + std::to_string(int(stop_s)) + "s");
    write(file, payload);
    std::printf("%s: %zu bytes, %zu images\n", file.c_str(), payload.size(),
                filter.images().size());
  }
  return 0;
}
