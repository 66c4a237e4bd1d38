// navd config loader: sim.yaml / rov.yaml load cleanly; unknown keys, wrong types, out-of-range
// values and missing required keys stop with the key path and the reason.
#include "nav/daemon/config/config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

namespace nav::daemon {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// config/ of this checkout (NAV_SOURCE_DIR, cmake/NavTargets.cmake).
std::filesystem::path config_dir() { return std::filesystem::path(NAV_SOURCE_DIR) / "config"; }

const char* kMinimal = R"(
sensors:
  - name: dvl
    type: dvl_pd0
    transport: {type: serial, device: /dev/ttyUSB0}
)";

/// Parses `yaml` expecting a ConfigError; returns it.
ConfigError expect_error(const std::string& yaml) {
  try {
    parse_config(yaml, "test.yaml");
  } catch (const ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "no ConfigError for:\n" << yaml;
  return ConfigError("", "", "");
}

TEST(Config, MinimalTakesTableTwoDefaults) {
  const NavdConfig c = parse_config(kMinimal);
  ASSERT_EQ(c.sensors.size(), 1u);
  const SensorConfig& s = c.sensors[0];
  EXPECT_EQ(s.name, "dvl");
  EXPECT_EQ(s.type, SensorType::kDvlPd0);
  const auto* serial = std::get_if<SerialTransport>(&s.transport);
  ASSERT_NE(serial, nullptr);
  EXPECT_EQ(serial->device, "/dev/ttyUSB0");
  EXPECT_EQ(serial->baud, 115200);
  EXPECT_NEAR(s.noise.roll_pitch_rad, 0.1 * kDeg, 1e-15);
  EXPECT_NEAR(s.noise.heading_rad, 0.1 * kDeg, 1e-15);
  EXPECT_DOUBLE_EQ(s.noise.velocity_mps, 0.01);
  EXPECT_DOUBLE_EQ(s.noise.depth_m, 0.01);
  EXPECT_DOUBLE_EQ(s.noise.altitude_m, 0.1);
  EXPECT_DOUBLE_EQ(c.filter.latency_window_ms, 200.0);
  EXPECT_EQ(c.checkpoint.keep, 3);
}

TEST(Config, SimYamlLoads) {
  const NavdConfig c = load_config_file((config_dir() / "sim.yaml").string());
  ASSERT_EQ(c.sensors.size(), 5u);
  for (const SensorConfig& s : c.sensors) {
    EXPECT_TRUE(std::holds_alternative<SimTransport>(s.transport)) << s.name;
  }
  EXPECT_NEAR(c.sensors[0].mount.rpy_rad[2], 45.0 * kDeg, 1e-12);
  EXPECT_DOUBLE_EQ(c.sensors[0].mount.lever_arm_m[0], 0.5);
  const SensorConfig& cam = c.sensors[4];
  EXPECT_EQ(cam.type, SensorType::kCameraGige);
  EXPECT_DOUBLE_EQ(cam.camera.fx_px, 1000.0);
  EXPECT_EQ(cam.camera.distortion.size(), 5u);
  EXPECT_EQ(cam.camera.pixel_format, PixelFormat::kMono12);
  EXPECT_EQ(cam.camera.trigger, Trigger::kSoftware);
  EXPECT_EQ(c.lcm.url, "udpm://239.255.76.67:7667?ttl=0");  // this machine only
  // Process noise measured from the simulated vehicle (config/README.md "filter"); heave at 4x
  // its measured value (docs/consistency.md "Process noise").
  EXPECT_DOUBLE_EQ(c.filter.process_noise.accel_psd[0], 1e-3);
  EXPECT_DOUBLE_EQ(c.filter.process_noise.accel_psd[1], 3e-5);
  EXPECT_DOUBLE_EQ(c.filter.process_noise.accel_psd[2], 2e-2);
  EXPECT_DOUBLE_EQ(c.filter.process_noise.angular_accel_psd[2], 6e-4);
  EXPECT_TRUE(c.filter.process_noise.validate().ok());
  EXPECT_DOUBLE_EQ(c.filter.process_noise.attitude_restoring.natural_period_s[1], 9.0);
  // Latencies the survey simulator applies (config/README.md).
  EXPECT_DOUBLE_EQ(c.sensors[0].latency_s, 0.1);
  EXPECT_DOUBLE_EQ(c.sensors[1].latency_s, 0.02);
  EXPECT_DOUBLE_EQ(c.sensors[2].latency_s, 0.05);
  EXPECT_DOUBLE_EQ(c.sensors[3].latency_s, 0.05);
  EXPECT_DOUBLE_EQ(c.sensors[2].pressure.latitude_deg, 41.73);
  ASSERT_TRUE(c.sim.has_value());  // the default mode's dive
  EXPECT_EQ(c.sim->dive_dir, "build/sim-dive");
  EXPECT_EQ(c.sim->seed, 1);
  EXPECT_EQ(c.sim->images, 866);
}

TEST(Config, SimSection) {
  EXPECT_FALSE(parse_config(kMinimal).sim.has_value());
  const NavdConfig c = parse_config(std::string(kMinimal) + "sim: {dive_dir: d, images: 12}\n");
  ASSERT_TRUE(c.sim.has_value());
  EXPECT_EQ(c.sim->dive_dir, "d");
  EXPECT_EQ(c.sim->images, 12);
  EXPECT_EQ(c.sim->seed, 1);
  EXPECT_DOUBLE_EQ(c.sim->outlier_rate, 0.05);
  EXPECT_EQ(expect_error(std::string(kMinimal) + "sim: {images: 12}\n").key_path(),
            "sim.dive_dir");
  EXPECT_EQ(expect_error(std::string(kMinimal) + "sim: {dive_dir: d, images: 1}\n").key_path(),
            "sim.images");
  EXPECT_EQ(expect_error(std::string(kMinimal) + "sim: {dive_dir: d, seeds: 1}\n").key_path(),
            "sim.seeds");
}

TEST(Config, RealtimeSection) {
  const RealtimeConfig off = parse_config(kMinimal).realtime;  // normal scheduling by default
  EXPECT_EQ(off.device_priority, 0);
  EXPECT_EQ(off.filter_priority, 0);
  EXPECT_FALSE(off.lock_memory);
  const RealtimeConfig on =
      parse_config(std::string(kMinimal) +
                   "realtime: {device_priority: 45, filter_priority: 20, lock_memory: true}\n")
          .realtime;
  EXPECT_EQ(on.device_priority, 45);
  EXPECT_EQ(on.filter_priority, 20);
  EXPECT_TRUE(on.lock_memory);
  ConfigError e = expect_error(std::string(kMinimal) + "realtime: {device_priority: 100}\n");
  EXPECT_EQ(e.key_path(), "realtime.device_priority");
  e = expect_error(std::string(kMinimal) + "realtime: {filter_priority: -1}\n");
  EXPECT_EQ(e.key_path(), "realtime.filter_priority");
  e = expect_error(std::string(kMinimal) + "realtime: {lock_memory: sometimes}\n");
  EXPECT_EQ(e.key_path(), "realtime.lock_memory");
  EXPECT_EQ(expect_error(std::string(kMinimal) + "realtime: {priority: 1}\n").key_path(),
            "realtime.priority");
}

TEST(Config, RegistrationKeys) {
  NavdConfig c = parse_config(kMinimal);
  EXPECT_DOUBLE_EQ(c.filter.registration_wait_s, 0.0);  // replay: a complete table
  EXPECT_EQ(c.filter.max_pending_registrations, 256);
  EXPECT_EQ(c.lcm.registration.name, "NAV_REGISTRATION");
  EXPECT_EQ(c.lcm.link_proposals.name, "NAV_LINK_PROPOSAL");
  c = parse_config(std::string(kMinimal) +
                   "filter: {registration_wait_s: 12.5, max_pending_registrations: 9}\n"
                   "lcm: {channels: {registration: {name: VISION_REG}, "
                   "link_proposals: {name: VISION_ASK}}}\n");
  EXPECT_DOUBLE_EQ(c.filter.registration_wait_s, 12.5);
  EXPECT_EQ(c.filter.max_pending_registrations, 9);
  EXPECT_EQ(c.lcm.registration.name, "VISION_REG");
  EXPECT_EQ(c.lcm.link_proposals.name, "VISION_ASK");
  ConfigError e = expect_error(std::string(kMinimal) + "filter: {registration_wait_s: 4000}\n");
  EXPECT_EQ(e.key_path(), "filter.registration_wait_s");
  e = expect_error(std::string(kMinimal) + "filter: {max_pending_registrations: 0}\n");
  EXPECT_EQ(e.key_path(), "filter.max_pending_registrations");
}

TEST(Config, RecoveryPreconditionerNames) {
  EXPECT_EQ(parse_config(kMinimal).filter.recovery_preconditioner,
            core::RecoveryPreconditioner::kBlockJacobi);
  NavdConfig c = parse_config(std::string(kMinimal) + "filter: {recovery_preconditioner: factor}\n");
  EXPECT_EQ(c.filter.recovery_preconditioner, core::RecoveryPreconditioner::kFactor);
  EXPECT_FALSE(c.filter.recovery_keep_factor_equal);
  c = parse_config(std::string(kMinimal) + "filter: {recovery_preconditioner: kept_factor}\n");
  EXPECT_EQ(c.filter.recovery_preconditioner, core::RecoveryPreconditioner::kFactor);
  EXPECT_TRUE(c.filter.recovery_keep_factor_equal);
  const ConfigError e =
      expect_error(std::string(kMinimal) + "filter: {recovery_preconditioner: cholesky}\n");
  EXPECT_EQ(e.key_path(), "filter.recovery_preconditioner");
  EXPECT_NE(e.reason().find("block_jacobi, factor or kept_factor"), std::string::npos) << e.what();
}

TEST(Config, KeptFactorRecentStates) {
  EXPECT_EQ(parse_config(kMinimal).filter.recovery_kept_recent_states,
            core::StateRecoveryOptions{}.kept_factor_recent_blocks);
  const NavdConfig c =
      parse_config(std::string(kMinimal) + "filter: {recovery_kept_recent_states: 64}\n");
  EXPECT_EQ(c.filter.recovery_kept_recent_states, 64);
  const ConfigError e =
      expect_error(std::string(kMinimal) + "filter: {recovery_kept_recent_states: -1}\n");
  EXPECT_EQ(e.key_path(), "filter.recovery_kept_recent_states");
}

TEST(Config, RenewalLagAndGrowth) {
  EXPECT_EQ(parse_config(kMinimal).filter.recovery_renewal_lag, 0);
  const std::string kept = std::string(kMinimal) +
                           "filter: {recovery_preconditioner: kept_factor, " +
                           "recovery_refresh_interval: 40, recovery_renewal_lag: ";
  EXPECT_EQ(parse_config(kept + "8}\n").filter.recovery_renewal_lag, 8);
  EXPECT_EQ(parse_config(kept + "8}\n").filter.recovery_refresh_interval, 40);
  EXPECT_EQ(parse_config(kMinimal).filter.recovery_refresh_growth, 0.0);
  EXPECT_EQ(parse_config(std::string(kMinimal) + "filter: {recovery_refresh_growth: 0.25}\n")
                .filter.recovery_refresh_growth,
            0.25);
  EXPECT_EQ(
      expect_error(std::string(kMinimal) + "filter: {recovery_refresh_growth: -1}\n").key_path(),
      "filter.recovery_refresh_growth");
  for (const std::string& bad :
       {kept + "40}\n", kept + "-1}\n",
        std::string(kMinimal) + "filter: {recovery_preconditioner: factor, "
                                "recovery_refresh_interval: 40, recovery_renewal_lag: 8}\n",
        std::string(kMinimal) + "filter: {recovery_renewal_lag: 1}\n"}) {
    const ConfigError e = expect_error(bad);
    EXPECT_EQ(e.key_path(), "filter.recovery_renewal_lag") << bad;
  }
}

TEST(Config, RegistrationSigningKeys) {
  NavdConfig c = parse_config(kMinimal);
  EXPECT_TRUE(c.lcm.registration_signing.key_file.empty());  // off by default
  c = parse_config(std::string(kMinimal) +
                   "lcm: {registration_signing: {key_file: /etc/navd/k, window_s: 0.5}}\n");
  EXPECT_EQ(c.lcm.registration_signing.key_file, "/etc/navd/k");
  EXPECT_DOUBLE_EQ(c.lcm.registration_signing.window_s, 0.5);
  ConfigError e = expect_error(std::string(kMinimal) + "lcm: {registration_signing: {}}\n");
  EXPECT_EQ(e.key_path(), "lcm.registration_signing.key_file");
  e = expect_error(std::string(kMinimal) +
                   "lcm: {registration_signing: {key_file: k, window_s: 0}}\n");
  EXPECT_EQ(e.key_path(), "lcm.registration_signing.window_s");
  e = expect_error(std::string(kMinimal) + "lcm: {registration_signing: {key_file: \"\"}}\n");
  EXPECT_EQ(e.key_path(), "lcm.registration_signing.key_file");
}

TEST(Config, RovYamlLoads) {
  const NavdConfig c = load_config_file((config_dir() / "rov.yaml").string());
  ASSERT_EQ(c.sensors.size(), 7u);
  const auto* fog = std::get_if<SerialTransport>(&c.sensors[2].transport);
  ASSERT_NE(fog, nullptr);
  EXPECT_EQ(fog->baud, 921600);
  EXPECT_EQ(fog->flow, FlowControl::kRtsCts);
  const auto* can = std::get_if<CanTransport>(&c.sensors[5].transport);
  ASSERT_NE(can, nullptr);
  EXPECT_EQ(can->interface, "can0");
  EXPECT_TRUE(c.filter.recovery_thread);  // the vehicle recovers beside the filter thread
  EXPECT_TRUE(c.filter.recovery_keep_factor_equal);  // with the factor kept equal to Λ
  EXPECT_EQ(c.filter.recovery_refresh_interval, 10);
  EXPECT_DOUBLE_EQ(c.filter.registration_wait_s, 30.0);  // the vision stage answers later
  EXPECT_GT(c.realtime.device_priority, c.realtime.filter_priority);  // devices preempt the filter
  EXPECT_GT(c.realtime.filter_priority, 0);
  EXPECT_TRUE(c.realtime.lock_memory);
  // Relative to rov.yaml's directory, loaded and validated with the config.
  EXPECT_EQ(can->signals_file, (config_dir() / "can/dvl_fog_example.yaml").string());
  EXPECT_FALSE(can->signals.messages.empty());
  const auto* gige = std::get_if<GigeTransport>(&c.sensors[6].transport);
  ASSERT_NE(gige, nullptr);
  EXPECT_EQ(c.sensors[6].camera.trigger, Trigger::kHardware);
  EXPECT_EQ(c.checkpoint.keep, 5);
  EXPECT_DOUBLE_EQ(c.filter.latency_window_ms, 250.0);
  EXPECT_EQ(c.sensors[3].type, SensorType::kPressureParo);
  EXPECT_GT(c.sensors[3].latency_s, 0.0);
}

TEST(Config, WrongBaudNamesTheKeyPath) {
  const ConfigError e = expect_error(R"(
sensors:
  - {name: a, type: altimeter, transport: {type: sim}}
  - {name: b, type: altimeter, transport: {type: sim}}
  - name: c
    type: pressure_paro
    transport: {type: serial, device: /dev/ttyS0, baud: 12345}
)");
  EXPECT_EQ(e.key_path(), "sensors[2].transport.baud");
  EXPECT_NE(e.reason().find("12345 is not a standard baud rate"), std::string::npos) << e.what();
  EXPECT_EQ(std::string(e.what()).rfind("test.yaml: sensors[2].transport.baud: ", 0), 0u)
      << e.what();
}

TEST(Config, UnknownKeysAreErrorsAtEveryLevel) {
  EXPECT_EQ(expect_error(std::string(kMinimal) + "filtr: {}\n").key_path(), "filtr");
  EXPECT_EQ(expect_error(std::string(kMinimal) + "filter: {latency_ms: 3}\n").key_path(),
            "filter.latency_ms");
  EXPECT_EQ(expect_error(R"(
sensors:
  - {name: d, type: dvl_pd0, transport: {type: serial, device: /dev/x, bauds: 9600}}
)")
                .key_path(),
            "sensors[0].transport.bauds");
  const ConfigError e = expect_error(R"(
sensors:
  - {name: d, type: dvl_pd0, transport: {type: sim}, noise: {depth_m: 0.1}}
)");
  EXPECT_EQ(e.key_path(), "sensors[0].noise.depth_m");
  EXPECT_NE(e.reason().find("unknown key (allowed: velocity_mps)"), std::string::npos) << e.what();
}

TEST(Config, WrongTypes) {
  ConfigError e = expect_error(std::string(kMinimal) + "filter: {cg_iterations_per_step: 2.5}\n");
  EXPECT_EQ(e.key_path(), "filter.cg_iterations_per_step");
  EXPECT_NE(e.reason().find("expected an integer, got '2.5'"), std::string::npos) << e.what();
  e = expect_error(std::string(kMinimal) + "filter: {latency_window_ms: soon}\n");
  EXPECT_EQ(e.key_path(), "filter.latency_window_ms");
  EXPECT_NE(e.reason().find("expected a number"), std::string::npos);
  e = expect_error(std::string(kMinimal) + "lcm: {url: [a, b]}\n");
  EXPECT_EQ(e.key_path(), "lcm.url");
  EXPECT_NE(e.reason().find("expected a string, got a sequence"), std::string::npos);
  e = expect_error("sensors: {name: x}\n");
  EXPECT_EQ(e.key_path(), "sensors");
  EXPECT_NE(e.reason().find("expected a sequence"), std::string::npos);
  e = expect_error(std::string(kMinimal) + "filter: {latency_window_ms: .nan}\n");
  EXPECT_NE(e.reason().find("not finite"), std::string::npos) << e.what();
}

TEST(Config, OutOfRangeValues) {
  ConfigError e = expect_error(std::string(kMinimal) + "filter: {latency_window_ms: -1}\n");
  EXPECT_EQ(e.key_path(), "filter.latency_window_ms");
  EXPECT_NE(e.reason().find("-1 is not in [0, 60000]"), std::string::npos) << e.what();
  e = expect_error(std::string(kMinimal) + "checkpoint: {keep: 0}\n");
  EXPECT_EQ(e.key_path(), "checkpoint.keep");
  e = expect_error(R"(
sensors:
  - {name: d, type: dvl_pd0, transport: {type: sim}, mount: {lever_arm_m: [0, 0, 1000]}}
)");
  EXPECT_EQ(e.key_path(), "sensors[0].mount.lever_arm_m[2]");
  e = expect_error(R"(
sensors:
  - {name: d, type: dvl_pd0, transport: {type: sim}, mount: {rotation_deg: [0, 0]}}
)");
  EXPECT_EQ(e.key_path(), "sensors[0].mount.rotation_deg");
  EXPECT_NE(e.reason().find("expected 3 numbers, got 2"), std::string::npos);
  e = expect_error(std::string(kMinimal) +
                   "filter: {process_noise_psd: {accel_m2ps3: [1, -1, 1]}}\n");
  EXPECT_EQ(e.key_path(), "filter.process_noise_psd.accel_m2ps3[1]");
}

TEST(Config, AttitudeRestoringKeys) {
  NavdConfig c = parse_config(kMinimal);
  EXPECT_FALSE(c.filter.process_noise.attitude_restoring.enabled());  // random walks by default
  c = parse_config(
      std::string(kMinimal) +
      "filter: {attitude_restoring: {natural_period_s: [7.3, 9], damping_ratio: [0.2, 0.1], "
      "trim_deg: [0, 1.5], pitch_per_heave_deg_per_mps: -6}}\n");
  const core::AttitudeRestoringOptions& a = c.filter.process_noise.attitude_restoring;
  EXPECT_DOUBLE_EQ(a.natural_period_s[0], 7.3);
  EXPECT_DOUBLE_EQ(a.damping_ratio[1], 0.1);
  EXPECT_DOUBLE_EQ(a.trim_rad[1], 1.5 * std::numbers::pi / 180.0);
  EXPECT_DOUBLE_EQ(a.pitch_per_heave_rad_per_mps, -6.0 * std::numbers::pi / 180.0);
  ConfigError e = expect_error(std::string(kMinimal) +
                               "filter: {attitude_restoring: {natural_period_s: [7.3, -1]}}\n");
  EXPECT_EQ(e.key_path(), "filter.attitude_restoring.natural_period_s[1]");
  e = expect_error(std::string(kMinimal) +
                   "filter: {attitude_restoring: {natural_period_s: [7.3]}}\n");
  EXPECT_NE(e.reason().find("expected 2 numbers [roll, pitch], got 1"), std::string::npos);
  e = expect_error(std::string(kMinimal) + "filter: {attitude_restoring: {periods: [1, 1]}}\n");
  EXPECT_EQ(e.key_path(), "filter.attitude_restoring.periods");
  EXPECT_NE(e.reason().find("unknown key"), std::string::npos) << e.reason();
}

TEST(Config, RecoveryThreadKeys) {
  NavdConfig c = parse_config(kMinimal);
  EXPECT_FALSE(c.filter.recovery_thread);
  EXPECT_DOUBLE_EQ(c.filter.recovery_handoff_s, 10.0);
  c = parse_config(std::string(kMinimal) +
                   "filter: {recovery_thread: true, recovery_handoff_s: 7.5}\n");
  EXPECT_TRUE(c.filter.recovery_thread);
  EXPECT_DOUBLE_EQ(c.filter.recovery_handoff_s, 7.5);
  ConfigError e = expect_error(std::string(kMinimal) + "filter: {recovery_handoff_s: -0.5}\n");
  EXPECT_EQ(e.key_path(), "filter.recovery_handoff_s");
  EXPECT_NE(e.reason().find("is not in [0, 3600]"), std::string::npos) << e.what();
  e = expect_error(std::string(kMinimal) + "filter: {recovery_thread: maybe}\n");
  EXPECT_EQ(e.key_path(), "filter.recovery_thread");
}

TEST(Config, MissingRequiredKeys) {
  EXPECT_EQ(expect_error("filter: {}\n").key_path(), "sensors");
  EXPECT_EQ(expect_error("sensors:\n  - {type: altimeter, transport: {type: sim}}\n").key_path(),
            "sensors[0].name");
  EXPECT_EQ(expect_error("sensors:\n  - {name: a, transport: {type: sim}}\n").key_path(),
            "sensors[0].type");
  EXPECT_EQ(expect_error("sensors:\n  - {name: a, type: altimeter, transport: {type: serial}}\n")
                .key_path(),
            "sensors[0].transport.device");
  const ConfigError e = expect_error(
      "sensors:\n  - {name: c, type: camera_v4l2, transport: {type: v4l2, device: /dev/video0}}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].camera");
  EXPECT_EQ(e.reason(), "missing required key");
  EXPECT_EQ(
      expect_error("sensors:\n  - name: c\n    type: camera_v4l2\n    transport: {type: sim}\n"
                   "    camera: {fx: 1, fy: 1, cx: 1}\n")
          .key_path(),
      "sensors[0].camera.cy");
}

TEST(Config, SensorSemantics) {
  ConfigError e = expect_error(
      "sensors:\n  - {name: a, type: dvl_can, transport: {type: serial, device: /dev/x}}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].transport.type");
  EXPECT_NE(e.reason().find("not valid for a dvl_can sensor"), std::string::npos) << e.what();
  e = expect_error("sensors:\n  - {name: a, type: sonar, transport: {type: sim}}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].type");
  EXPECT_NE(e.reason().find("'sonar' is not one of: dvl_pd0"), std::string::npos);
  e = expect_error(
      "sensors:\n  - {name: a, type: altimeter, transport: {type: sim}}\n"
      "  - {name: a, type: altimeter, transport: {type: sim}}\n");
  EXPECT_EQ(e.key_path(), "sensors[1].name");
  EXPECT_NE(e.reason().find("duplicate"), std::string::npos);
  e = expect_error(
      "sensors:\n  - {name: a, type: altimeter, transport: {type: sim}, camera: {fx: 1}}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].camera");
  e = expect_error(
      "sensors:\n  - name: c\n    type: camera_gige\n    transport: {type: sim}\n"
      "    camera: {fx: 1, fy: 1, cx: 1, cy: 1, distortion: [1, 2, 3]}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].camera.distortion");
  e = expect_error("sensors: []\n");
  EXPECT_EQ(e.key_path(), "sensors");
  e = expect_error(std::string(kMinimal) + "lcm: {url: 'tcp://x'}\n");
  EXPECT_EQ(e.key_path(), "lcm.url");
}

TEST(Config, LatencyAndPressureKeys) {
  NavdConfig c = parse_config(
      "sensors:\n  - name: p\n    type: pressure_paro\n    transport: {type: sim}\n"
      "    latency_ms: 50\n    pressure: {latitude_deg: -33.5, surface_pressure_dbar: 10.2}\n"
      "  - {name: a, type: altimeter, transport: {type: sim}}\n");
  EXPECT_DOUBLE_EQ(c.sensors[0].latency_s, 0.05);
  EXPECT_DOUBLE_EQ(c.sensors[0].pressure.latitude_deg, -33.5);
  EXPECT_DOUBLE_EQ(c.sensors[0].pressure.surface_pressure_dbar, 10.2);
  EXPECT_DOUBLE_EQ(c.sensors[1].latency_s, 0.0);  // default: no latency
  EXPECT_DOUBLE_EQ(c.sensors[1].pressure.surface_pressure_dbar, 10.1325);

  ConfigError e = expect_error(
      "sensors:\n  - {name: a, type: altimeter, transport: {type: sim}, latency_ms: 10001}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].latency_ms");
  e = expect_error(
      "sensors:\n  - {name: a, type: altimeter, transport: {type: sim}, latency_ms: -1}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].latency_ms");
  e = expect_error(
      "sensors:\n  - {name: a, type: dvl_pd0, transport: {type: sim},"
      " pressure: {latitude_deg: 10}}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].pressure");
  EXPECT_NE(e.reason().find("only pressure_paro"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("dvl_pd0"), std::string::npos) << e.what();
  e = expect_error(
      "sensors:\n  - {name: p, type: pressure_paro, transport: {type: sim},"
      " pressure: {latitude_deg: 91}}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].pressure.latitude_deg");
  e = expect_error(
      "sensors:\n  - {name: p, type: pressure_paro, transport: {type: sim},"
      " pressure: {surface_pressure_dbar: 21}}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].pressure.surface_pressure_dbar");
  e = expect_error(
      "sensors:\n  - {name: p, type: pressure_paro, transport: {type: sim},"
      " pressure: {latitude: 10}}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].pressure.latitude");
}

TEST(Config, CameraImageDirectory) {
  const NavdConfig c = parse_config(
      "sensors:\n  - name: c\n    type: camera_gige\n    transport: {type: sim}\n"
      "    camera: {fx: 1, fy: 1, cx: 1, cy: 1, image_dir: /data/dive/images}\n");
  EXPECT_EQ(c.sensors[0].camera.image_dir, "/data/dive/images");
  EXPECT_EQ(expect_error("sensors:\n  - name: c\n    type: camera_gige\n    transport: {type: "
                         "sim}\n    camera: {fx: 1, fy: 1, cx: 1, cy: 1, image_dir: [1]}\n")
                .key_path(),
            "sensors[0].camera.image_dir");
}

TEST(Config, BadCanSignalTableStopsAtTheKey) {
  const std::string table = testing::TempDir() + "navd_config_test_bad_can.yaml";
  {
    std::ofstream out(table);
    out << "messages:\n  - {name: m, id: 0x100, dlc: 8, signals: [{name: s, start_bit: 0, "
           "length: 0, byte_order: intel}]}\n";
  }
  const ConfigError e = expect_error(
      "sensors:\n  - {name: c, type: dvl_can, transport: {type: can, interface: can0, "
      "signals_file: " +
      table + "}}\n");
  EXPECT_EQ(e.key_path(), "sensors[0].transport.signals_file");
  EXPECT_NE(e.reason().find("length"), std::string::npos) << e.what();
  std::remove(table.c_str());
  EXPECT_EQ(expect_error("sensors:\n  - {name: c, type: dvl_can, transport: {type: can, "
                         "interface: can0, signals_file: /nonexistent/can.yaml}}\n")
                .key_path(),
            "sensors[0].transport.signals_file");
}

TEST(Config, NoiseInDegreesStoredInRadians) {
  const NavdConfig c = parse_config(
      "sensors:\n  - {name: h, type: heading_nmea, transport: {type: sim},"
      " noise: {heading_deg: 0.5, roll_pitch_deg: 0.2}}\n");
  EXPECT_NEAR(c.sensors[0].noise.heading_rad, 0.5 * kDeg, 1e-15);
  EXPECT_NEAR(c.sensors[0].noise.roll_pitch_rad, 0.2 * kDeg, 1e-15);
}

TEST(Config, SyntaxAndFileErrors) {
  ConfigError e = expect_error("sensors: [\n");
  EXPECT_EQ(e.key_path(), "");
  EXPECT_NE(e.reason().find("YAML syntax error at line"), std::string::npos) << e.what();
  try {
    load_config_file("/nonexistent/navd.yaml");
    ADD_FAILURE() << "no error for a missing file";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("/nonexistent/navd.yaml"), std::string::npos);
    EXPECT_EQ(error.reason(), "cannot open file");
  }
}

}  // namespace
}  // namespace nav::daemon
