// `navtool sensors --config C [--duration-s S] [--lcm-url U]`: runs navd's device threads
// (daemon/include/nav/daemon/sources/device_sources.h) without the filter, to check the
// vehicle's sensors before a dive and to feed `lcm-logger` (RAW_<NAME>, NAV_IMAGE) when recording
// a dive without navd. Measurements are decoded and counted, then discarded. Ends after the
// duration or on SIGINT/SIGTERM and prints one JSON object with each device sensor's health.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <thread>

#include "nav/daemon/config/config.h"
#include "nav/daemon/system/host_clock.h"
#include "nav/daemon/sources/device_sources.h"
#include "navtool/commands.h"

namespace nav::tool {
namespace {

struct SensorsArgs {
  std::string config_path;
  double duration_s = 0.0;
  std::string lcm_url;
};

/// Waits for the duration (0: forever) or SIGINT/SIGTERM (blocked in every thread).
void wait_for_end(double duration_s) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  const timespec tick{0, 20'000'000};
  const std::int64_t start = daemon::monotonic_us();
  while (duration_s <= 0.0 || (daemon::monotonic_us() - start) * 1e-6 < duration_s) {
    if (sigtimedwait(&set, nullptr, &tick) > 0) return;
  }
}

nlohmann::json health_json(const navlcm::sensor_health_t& h) {
  return {{"name", h.name},
          {"connected", h.connected},
          {"records", h.records},
          {"measurements", h.measurements},
          {"bytes", h.bytes},
          {"decode_errors", h.decode_errors},
          {"dropped_bytes", h.dropped_bytes},
          {"queue_drops", h.queue_drops},
          {"reconnects", h.reconnects},
          {"rate_hz", h.rate_hz},
          {"last_message_age_s", h.last_message_age_s}};
}

void run_sensors(const SensorsArgs& args) {
  // The device threads log with spdlog; navtool's stdout carries only the JSON result.
  if (!spdlog::get("navtool-sensors")) {
    spdlog::set_default_logger(spdlog::stderr_color_mt("navtool-sensors"));
  }
  daemon::NavdConfig config;
  try {
    config = daemon::load_config_file(args.config_path);
  } catch (const daemon::ConfigError& e) {
    throw CommandError(e.what());
  }
  if (!args.lcm_url.empty()) config.lcm.url = args.lcm_url;
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);  // before any thread starts

  lcm::LCM lcm(config.lcm.url);
  if (!lcm.good())
    std::fprintf(stderr, "navtool sensors: cannot open LCM at %s\n", config.lcm.url.c_str());
  daemon::MeasurementQueue queue(4096);
  daemon::SensorHealthBoard health(config);
  daemon::DeviceSources sources(config, queue, lcm.good() ? &lcm : nullptr, health);
  std::atomic<bool> stop{false};
  std::uint64_t measurements = 0;
  std::thread consumer([&] {
    std::vector<daemon::Measurement> batch;
    while (!stop.load()) {
      batch.clear();
      measurements += queue.pop_bulk(batch, 1024);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  });
  const std::int64_t start_us = daemon::monotonic_us();
  health.snapshot(start_us);
  const std::size_t threads = sources.start(stop);
  if (threads == 0)
    std::fprintf(stderr, "navtool sensors: no sensor with a device in %s\n",
                 args.config_path.c_str());
  wait_for_end(args.duration_s);
  stop.store(true);
  sources.join();
  consumer.join();
  std::vector<daemon::Measurement> rest;
  measurements += queue.pop_bulk(rest, 1 << 20);
  nlohmann::json out = {{"device_threads", threads},
                        {"measurements", measurements},
                        {"raw_published", sources.publisher().published()},
                        {"sensors", nlohmann::json::array()}};
  for (const auto& h : health.snapshot(daemon::monotonic_us()))
    out["sensors"].push_back(health_json(h));
  std::printf("%s\n", out.dump().c_str());
}

void add_sensors(CLI::App& app) {
  auto args = std::make_shared<SensorsArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sensors",
      "Run navd's device threads (every sensor whose transport is not sim) without the filter: "
      "publish RAW_<NAME> / NAV_IMAGE on LCM (for lcm-logger), decode, and print each sensor's "
      "health as JSON at the end (duration or SIGINT/SIGTERM).");
  cmd->add_option("--config", args->config_path, "navd YAML configuration")->required();
  cmd->add_option("--duration-s", args->duration_s, "stop after this many seconds (0: on a signal)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--lcm-url", args->lcm_url, "LCM URL (overrides lcm.url)");
  cmd->callback([args] { run_sensors(*args); });
}

const CommandRegistration kRegister{"sensors", add_sensors};

}  // namespace
}  // namespace nav::tool
