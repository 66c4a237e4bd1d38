#pragma once
// navd configuration (YAML, yaml-cpp): the typed NavdConfig and its loader. Every key is
// documented in config/README.md; config/sim.yaml and config/rov.yaml are complete examples.
//
// Start-up contract (docs/architecture.md): unknown keys, wrong types, out-of-range values and
// missing required keys stop start-up with a ConfigError naming the key path and the reason, e.g.
//   "rov.yaml: sensors[2].transport.baud: 12345 is not a standard baud rate (1200 ... 921600)".
// Units at this edge: angles in degrees (keys end in _deg), everything stored in SI / radians.
// Noise defaults are Table II of Eustice et al., "Visually Navigating the RMS Titanic with SLAM
// Information Filters" (RSS 2005): roll/pitch 0.1 deg, heading 0.1 deg, body velocities
// 0.01 m/s, depth 0.01 m, altitude 0.1 m (1 sigma).

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "nav/core/models/constant_velocity.h"
#include "nav/daemon/config/vision_config.h"
#include "nav/daemon/config/config_error.h"
#include "nav/daemon/config/filter_config.h"
#include "nav/drivers/config/can_config.h"

namespace nav::daemon {

enum class SensorType {
  kDvlPd0,        ///< "dvl_pd0": Teledyne RDI PD0 binary ensembles
  kDvlPd6,        ///< "dvl_pd6": PD6 ASCII
  kDvlCan,        ///< "dvl_can": DVL on CAN with a signal table
  kHeadingNmea,   ///< "heading_nmea": NMEA 0183 attitude/heading
  kFogKvh,        ///< "fog_kvh": KVH fibre-optic gyro
  kPressureParo,  ///< "pressure_paro": Paroscientific depth sensor
  kAltimeter,     ///< "altimeter"
  kCameraGige,    ///< "camera_gige": GigE Vision camera (Aravis)
  kCameraV4l2,    ///< "camera_v4l2": V4L2 camera
};
const char* to_string(SensorType type);
bool is_camera(SensorType type);

enum class Parity { kNone, kEven, kOdd };
enum class FlowControl { kNone, kRtsCts, kXonXoff };

struct SerialTransport {
  std::string device;                     ///< required, e.g. /dev/ttyUSB0
  int baud = 115200;                      ///< standard rate 1200 ... 921600
  Parity parity = Parity::kNone;          ///< none | even | odd
  FlowControl flow = FlowControl::kNone;  ///< none | rtscts | xonxoff
};
struct CanTransport {
  std::string interface;       ///< required, e.g. can0
  std::string signals_file;    ///< required, CAN signal table (config/can/*.yaml); a relative path
                               ///< is relative to the config file's directory
  drivers::CanConfig signals;  ///< the table, loaded and validated with the config
};
struct GigeTransport {
  std::string camera_id;  ///< required, Aravis device id
};
struct V4l2Transport {
  std::string device;  ///< required, e.g. /dev/video0
};
/// Data produced by navd's built-in survey simulator (no device).
struct SimTransport {};
using Transport =
    std::variant<SerialTransport, CanTransport, GigeTransport, V4l2Transport, SimTransport>;

/// Fixed sensor mount: R_body_sensor from Z-Y-X Euler angles, lever arm p_body_sensor_m.
struct Mount {
  std::array<double, 3> rpy_rad{0.0, 0.0, 0.0};      ///< YAML rotation_deg, each in [-360, 360]
  std::array<double, 3> lever_arm_m{0.0, 0.0, 0.0};  ///< YAML lever_arm_m, each |.| <= 100 m
};

/// 1-sigma measurement noise (Table II defaults). Each sensor type accepts only its own keys.
struct NoiseSigmas {
  double roll_pitch_rad = 0.1 * 3.14159265358979323846 / 180.0;  ///< roll_pitch_deg
  double heading_rad = 0.1 * 3.14159265358979323846 / 180.0;     ///< heading_deg
  double velocity_mps = 0.01;                                    ///< velocity_mps
  double depth_m = 0.01;                                         ///< depth_m
  double altitude_m = 0.1;                                       ///< altitude_m
  double pixel_px = 1.0;                                         ///< pixel_px (cameras)
};

enum class PixelFormat { kMono8, kMono12, kMono16, kBayerRg8, kRgb8 };
enum class Trigger { kFreeRun, kSoftware, kHardware };

/// Pinhole calibration with OpenCV distortion order (k1 k2 p1 p2 [k3 [k4 k5 k6]]).
struct CameraConfig {
  double fx_px = 0.0, fy_px = 0.0;  ///< required, [1e-3, 1e6]
  double cx_px = 0.0, cy_px = 0.0;  ///< required, [0, 1e5]
  std::vector<double> distortion;   ///< 0, 4, 5 or 8 coefficients
  PixelFormat pixel_format = PixelFormat::kMono8;
  Trigger trigger = Trigger::kFreeRun;
  double frame_rate_hz = 1.0;  ///< images per second [1e-3, 100]
  /// image_dir: where navd writes each frame as a 16-bit PNG (the dive directory's images/);
  /// empty (default): frames are not written.
  std::string image_dir;
};

/// Pressure-to-depth conversion (UNESCO 1983, drivers/codecs/seawater.h), pressure_paro only.
struct PressureConfig {
  double latitude_deg = 41.73;             ///< latitude_deg, [-90, 90] (default: RMS Titanic site)
  double surface_pressure_dbar = 10.1325;  ///< surface_pressure_dbar, atmosphere at the surface
};

struct SensorConfig {
  std::string name;  ///< required, unique
  SensorType type = SensorType::kDvlPd0;
  Transport transport = SimTransport{};
  Mount mount;
  NoiseSigmas noise;
  CameraConfig camera;      ///< required block for camera_* types, forbidden otherwise
  PressureConfig pressure;  ///< pressure_paro only
  /// latency_ms: time from validity to the host reading the last byte, subtracted from the
  /// host receive time for sensors whose messages carry no usable device time. [0, 10000]
  double latency_s = 0.0;
};

struct LcmChannel {
  std::string name;      ///< channel name, non-empty
  double rate_hz = 1.0;  ///< publish rate [1e-3, 1000]
};
/// lcm.registration_signing (registration_signature.h, config/README.md): off when key_file
/// is empty. Then every registration_t must carry a valid HMAC-SHA256 signature whose time is
/// within window_s of navd's clock and increasing per signer.
struct RegistrationSigningConfig {
  std::string key_file;   ///< hex key, mode 0600/0400, owned by navd's user ("" = off)
  double window_s = 5.0;  ///< [1e-3, 3600]
};
struct LcmConfig {
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  RegistrationSigningConfig registration_signing;
  LcmChannel nav_solution{"NAVD_SOLUTION", 10.0};
  LcmChannel health{"NAVD_HEALTH", 1.0};
  LcmChannel bounds{"NAVD_BOUNDS", 0.2};  ///< delayed_state_bound_t at each insert/tightening
  LcmChannel bounds_snapshot{"NAVD_BOUNDS_SNAPSHOT", 0.2};  ///< bounds_snapshot_t at rate_hz
  LcmChannel camera_links{"NAVD_CAMERA_LINKS", 1.0};        ///< camera_link_t per proposed pair
                                                            ///< (event-driven; rate_hz unused)
  /// registration_t navd's live mode subscribes to (the vision stage's answers; rate unused).
  LcmChannel registration{"NAV_REGISTRATION", 1.0};
  /// link_proposal_t per pair waiting for its registration (event-driven; rate unused).
  LcmChannel link_proposals{"NAV_LINK_PROPOSAL", 1.0};
};

struct CheckpointConfig {
  std::string path = "/var/lib/navd/checkpoints";  ///< directory
  double period_s = 60.0;                          ///< [1e-3, 86400]
  int keep = 3;                                    ///< newest K kept, [1, 100]
};

/// `sim`: navd's default mode (no --replay, no device sensor) simulates this dive with
/// nav::sim::simulate_dive when it is missing and replays it. Paths relative to the working
/// directory.
struct SimDiveConfig {
  std::string dive_dir;        ///< required in the section
  int seed = 1;                ///< [0, 2^31 - 1]
  int images = 866;            ///< [2, 100000]
  double outlier_rate = 0.05;  ///< [0, 1], fraction of registrations that are outliers
};

/// `realtime` (live mode only; nav/daemon/system/realtime.h): SCHED_FIFO priorities, 0 = normal
/// scheduling, each in [0, 99]; the serial and CAN device threads should be above the filter's.
struct RealtimeConfig {
  int device_priority = 0;   ///< serial and CAN device threads (they date records on arrival)
  int filter_priority = 0;   ///< the filter thread
  bool lock_memory = false;  ///< mlockall(MCL_CURRENT | MCL_FUTURE) at start
};

struct NavdConfig {
  std::vector<SensorConfig> sensors;  ///< required, at least one
  FilterConfig filter;
  LcmConfig lcm;
  CheckpointConfig checkpoint;
  RealtimeConfig realtime;
  std::optional<SimDiveConfig> sim;  ///< the `sim` section, if present
  VisionConfig vision;               ///< the `vision` section (vision_config.h)
};

/// Parses YAML text; `source` names it in errors; relative file names in it (CAN signal tables)
/// are resolved against `base_dir` (default: the working directory). Throws ConfigError.
NavdConfig parse_config(const std::string& yaml_text, const std::string& source = "<string>",
                        const std::string& base_dir = "");
/// Reads and parses a file (errors name the file; relative paths in it are relative to its
/// directory). Throws ConfigError, also if unreadable.
NavdConfig load_config_file(const std::string& path);

}  // namespace nav::daemon
