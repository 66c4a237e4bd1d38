// Device sources: a serial NMEA sensor over a pseudo-terminal (measurements in the queue, raw
// bytes on LCM memq://, reconnection after the device vanishes), a DVL on CAN through the
// transport interface (socketpair) and, when the kernel has one, a real CAN interface; queue
// overflow (drops counted, thread alive); a camera through the Camera interface (ImageEvents,
// NAV_IMAGE with thumbnail, 16-bit PNG).
#include "nav/daemon/sources/device_source.h"

#include <arv.h>
#include <gtest/gtest.h>
#include <pty.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/raw_bytes_t.hpp>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "nav/daemon/log/dive_log.h"
#include "nav/daemon/sources/camera_source.h"
#include "nav/daemon/sources/device_sources.h"
#include "nav/drivers/codecs/can_signals.h"
#include "nav/drivers/codecs/nmea.h"
#include "nav/drivers/config/can_config.h"
#include "nav/drivers/transports/serial_port.h"

namespace nav::daemon {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;
constexpr double kDeg = std::numbers::pi / 180.0;

SensorConfig sensor(const char* name, SensorType type) {
  static const std::string kEmpty;  // (GCC 12 -Wrestrict false positive on literal assignment)
  SensorConfig s;
  s.name = kEmpty + name;
  s.type = type;
  s.latency_s = 0.02;
  return s;
}

std::string hdt(double heading_deg) {
  drivers::NmeaHeading h;
  h.heading_rad = heading_deg * kDeg;
  return drivers::encode_nmea(h);
}

/// Collects what was published on LCM (memq://: delivered when the test calls handle).
class RawSink {
 public:
  explicit RawSink(lcm::LCM& lcm) : lcm_(lcm) { lcm.subscribe(".*", &RawSink::on_message, this); }
  void drain() {
    while (lcm_.handleTimeout(0) > 0) {
    }
  }
  void on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    channels.push_back(channel);
    if (channel.rfind("RAW_", 0) == 0) {
      navlcm::raw_bytes_t m;
      if (m.decode(buffer->data, 0, static_cast<int>(buffer->data_size)) > 0) raw.push_back(m);
    } else if (channel == kImageChannel) {
      navlcm::image_metadata_t m;
      if (m.decode(buffer->data, 0, static_cast<int>(buffer->data_size)) > 0) images.push_back(m);
    }
  }
  std::vector<std::string> channels;
  std::vector<navlcm::raw_bytes_t> raw;
  std::vector<navlcm::image_metadata_t> images;

 private:
  lcm::LCM& lcm_;
};

/// A pseudo-terminal; the test is the sensor on the master side.
struct Pty {
  Pty() {
    char name[256] = {};
    int slave = -1;
    if (::openpty(&master, &slave, name, nullptr, nullptr) != 0) return;
    slave_path = name;
    ::close(slave);
  }
  ~Pty() { close_master(); }
  void close_master() {
    if (master >= 0) ::close(master);
    master = -1;
  }
  void send(const std::string& s) const { (void)!::write(master, s.data(), s.size()); }
  int master = -1;
  std::string slave_path;
};

template <typename Pred>
bool wait_until(Pred pred, std::chrono::milliseconds timeout, const std::function<void()>& poke) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (pred()) return true;
    if (poke) poke();
    std::this_thread::sleep_for(20ms);
  }
  return pred();
}

TEST(DeviceSource, SerialNmeaOverAPtyReconnectsAfterTheDeviceVanishes) {
  const fs::path link = fs::temp_directory_path() / ("navd_dev_" + std::to_string(::getpid()));
  fs::remove(link);
  auto first = std::make_unique<Pty>();
  ASSERT_GE(first->master, 0);
  fs::create_symlink(first->slave_path, link);

  NavdConfig config;
  config.sensors.push_back(sensor("heading", SensorType::kHeadingNmea));
  SensorHealthBoard board(config);
  MeasurementQueue queue(1024);
  auto producer = queue.make_producer("heading");
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  LcmRawPublisher publisher(&lcm);
  RawSink sink(lcm);  // subscribed before publishing; handled after the thread stops
  auto decoder = make_sensor_decoder(config.sensors[0], 0);
  drivers::SerialOptions serial;
  serial.device = link.string();
  serial.baud = 115200;
  serial.reconnect_initial = 20ms;
  serial.reconnect_max = 100ms;
  drivers::SerialPort port(serial);
  std::atomic<bool> stop{false};
  DeviceLoopContext context{*decoder, producer, &publisher, board.at(0), stop, {}};
  context.options.read_timeout = 50ms;
  std::thread thread([&] { run_byte_device(port, context); });

  SensorHealth& h = board.at(0);
  ASSERT_TRUE(
      wait_until([&] { return h.messages.load() >= 5; }, 5s, [&] { first->send(hdt(10.0)); }));
  EXPECT_TRUE(h.connected.load());
  first->close_master();  // unplugged
  ASSERT_TRUE(wait_until([&] { return !h.connected.load(); }, 3s, nullptr));
  fs::remove(link);
  Pty second;  // plugged in again under the same name
  fs::create_symlink(second.slave_path, link);
  const std::uint64_t before = h.messages.load();
  ASSERT_TRUE(wait_until([&] { return h.messages.load() >= before + 5; }, 5s,
                         [&] { second.send(hdt(20.0)); }));
  stop.store(true);
  thread.join();
  fs::remove(link);

  EXPECT_EQ(h.disconnects.load(), 1u);
  EXPECT_EQ(h.reconnects.load(), 1u);
  EXPECT_EQ(h.queue_drops.load(), 0u);
  EXPECT_EQ(h.decode_errors.load(), 0u);
  std::vector<Measurement> got;
  queue.pop_bulk(got, 10000);
  ASSERT_EQ(got.size(), h.measurements.load());
  const auto& a = std::get<Attitude>(got.back());
  EXPECT_NEAR(a.heading_rad, 20.0 * kDeg, 1e-6);
  EXPECT_FALSE(a.has_roll_pitch);
  EXPECT_EQ(a.time.validity_us, a.time.host_monotonic_us - 20'000);

  // Every read went out on RAW_HEADING; replayed through a fresh decoder, the same measurements.
  sink.drain();
  ASSERT_FALSE(sink.raw.empty());
  auto replay = make_sensor_decoder(config.sensors[0], 0);
  std::vector<Measurement> replayed;
  std::uint64_t raw_bytes = 0;
  for (const auto& m : sink.raw) {
    EXPECT_EQ(m.device, "heading");
    raw_bytes += m.data.size();
    replay->feed(m.data, m.utime, m.host_monotonic_us, replayed);
  }
  EXPECT_EQ(sink.channels.front(), "RAW_HEADING");
  EXPECT_EQ(raw_bytes, h.bytes.load());
  ASSERT_EQ(replayed.size(), got.size());
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_EQ(validity_us(replayed[i]), validity_us(got[i]));
}

TEST(DeviceSource, QueueOverflowIsCountedAndTheThreadKeepsRunning) {
  NavdConfig config;
  config.sensors.push_back(sensor("heading", SensorType::kHeadingNmea));
  SensorHealthBoard board(config);
  MeasurementQueue queue(4);  // nobody consumes
  auto producer = queue.make_producer("heading");
  auto decoder = make_sensor_decoder(config.sensors[0], 0);
  drivers::MemoryByteStream stream("mem");
  std::string burst;
  for (int i = 0; i < 50; ++i) burst += hdt(i);
  stream.push({reinterpret_cast<const std::uint8_t*>(burst.data()), burst.size()},
              drivers::HostTime{1000, 2000});
  std::atomic<bool> stop{false};
  DeviceLoopContext context{*decoder, producer, nullptr, board.at(0), stop, {}};
  context.options.read_timeout = 20ms;
  std::thread thread([&] { run_byte_device(stream, context); });
  SensorHealth& h = board.at(0);
  ASSERT_TRUE(wait_until([&] { return h.messages.load() == 50; }, 3s, nullptr));
  EXPECT_EQ(h.queue_drops.load(), 46u);
  const std::string more = hdt(1.0);
  stream.push({reinterpret_cast<const std::uint8_t*>(more.data()), more.size()},
              drivers::HostTime{3000, 4000});
  EXPECT_TRUE(wait_until([&] { return h.messages.load() == 51; }, 3s, nullptr));  // alive
  EXPECT_EQ(h.queue_drops.load(), 47u);
  EXPECT_EQ(queue.total_dropped(), 47u);
  stop.store(true);
  thread.join();
}

// --- CAN --------------------------------------------------------------------------------------

fs::path can_example() {
  const fs::path rel = "config/can/dvl_fog_example.yaml";
  const auto beside = fs::path(__FILE__).parent_path().parent_path().parent_path();
  return fs::exists(beside / rel) ? beside / rel : rel;
}

SensorConfig can_dvl() {
  SensorConfig s = sensor("dvl_can", SensorType::kDvlCan);
  CanTransport can;
  can.interface = "can0";
  can.signals = drivers::load_can_config_file(can_example().string());
  s.transport = can;
  return s;
}

drivers::CanFrame frame_of(const drivers::CanMessageSpec& spec,
                           std::vector<drivers::CanSignalInput> values) {
  const auto data = drivers::encode_can_message(spec, values);
  drivers::CanFrame f;
  f.id = spec.id;
  f.extended = spec.extended;
  f.dlc = spec.dlc;
  if (data) std::copy(data->begin(), data->end(), f.data.begin());
  return f;
}

TEST(DeviceSource, CanDvlThroughTheTransportInterfaceReopensAClosedBus) {
  NavdConfig config;
  config.sensors.push_back(can_dvl());
  const auto& table = std::get<CanTransport>(config.sensors[0].transport).signals.messages;
  const auto spec = [&](const char* n) -> const drivers::CanMessageSpec& {
    return *std::find_if(table.begin(), table.end(), [&](const auto& m) { return m.name == n; });
  };
  SensorHealthBoard board(config);
  MeasurementQueue queue(1024);
  auto producer = queue.make_producer("dvl_can");
  lcm::LCM lcm("memq://");
  LcmRawPublisher publisher(&lcm);
  RawSink sink(lcm);
  auto decoder = make_sensor_decoder(config.sensors[0], 0);

  // Two buses in turn: the first peer closes (bus gone), the loop reopens and gets the second.
  std::vector<std::unique_ptr<drivers::SocketCanBus>> ours, theirs;
  for (int i = 0; i < 2; ++i) {
    ours.push_back(std::make_unique<drivers::SocketCanBus>());
    theirs.push_back(std::make_unique<drivers::SocketCanBus>());
    ASSERT_TRUE(drivers::open_can_socketpair(*ours.back(), *theirs.back()).ok());
  }
  std::atomic<int> opened{0};
  const CanBusOpener opener = [&](drivers::IoStatus& status) -> std::unique_ptr<drivers::CanBus> {
    const int k = opened.load();
    if (k >= 2) {
      status = drivers::IoStatus::Error(drivers::IoCode::kDisconnected, "can0", "gone");
      return nullptr;
    }
    opened.store(k + 1);
    return std::move(theirs[static_cast<std::size_t>(k)]);
  };
  std::atomic<bool> stop{false};
  DeviceLoopContext context{*decoder, producer, &publisher, board.at(0), stop, {}};
  context.options.read_timeout = 20ms;
  context.options.reconnect_initial = 10ms;
  std::thread thread([&] { run_can_device(opener, "can0", context); });

  SensorHealth& h = board.at(0);
  auto send_ping = [&](drivers::SocketCanBus& bus, int k) {
    const double seq = k % 256;
    ASSERT_TRUE(
        bus.send(frame_of(spec("dvl_time"), {{"time_s", 100.0 + 0.2 * k}, {"ping_seq", seq}}),
                 100ms)
            .ok());
    ASSERT_TRUE(bus.send(frame_of(spec("dvl_velocity"), {{"v_x_mps", 0.5},
                                                         {"v_y_mps", 0.1},
                                                         {"v_z_mps", 0.0},
                                                         {"bottom_track_valid", 1},
                                                         {"ping_seq", seq}}),
                         100ms)
                    .ok());
  };
  for (int k = 0; k < 5; ++k) send_ping(*ours[0], k);
  ASSERT_TRUE(wait_until([&] { return h.measurements.load() == 5; }, 3s, nullptr));
  ours[0]->close();  // the bus disappears
  ASSERT_TRUE(wait_until([&] { return opened.load() == 2; }, 3s, nullptr));
  for (int k = 5; k < 10; ++k) send_ping(*ours[1], k);
  ASSERT_TRUE(wait_until([&] { return h.measurements.load() == 10; }, 3s, nullptr));
  stop.store(true);
  thread.join();

  EXPECT_EQ(h.reconnects.load(), 1u);
  EXPECT_EQ(h.disconnects.load(), 1u);
  EXPECT_EQ(h.messages.load(), 20u);
  std::vector<Measurement> got;
  queue.pop_bulk(got, 100);
  ASSERT_EQ(got.size(), 10u);
  EXPECT_NEAR(std::get<DvlVelocity>(got[9]).v_sensor_mps[0], 0.5, 1e-3);
  sink.drain();
  ASSERT_EQ(sink.raw.size(), 20u);  // one candump line per frame on RAW_DVL_CAN
  EXPECT_EQ(sink.channels[0], "RAW_DVL_CAN");
  const std::string line(sink.raw[1].data.begin(), sink.raw[1].data.end());
  EXPECT_NE(line.find(" can0 200#"), std::string::npos) << line;
  auto replay = make_sensor_decoder(config.sensors[0], 0);
  std::vector<Measurement> replayed;
  for (const auto& m : sink.raw) replay->feed(m.data, m.utime, m.host_monotonic_us, replayed);
  EXPECT_EQ(replayed.size(), got.size());
  EXPECT_EQ(replay->counters().decode_errors, 0u);
}

TEST(DeviceSource, RealCanInterface) {
  drivers::SocketCanBus bus;
  const drivers::IoStatus status = bus.open_interface("can0");
  if (!status.ok()) {
    GTEST_SKIP() << "no CAN interface can0 on this machine (" << status.message()
                 << "); the CAN loop is tested through the socketpair transport above";
  }
  EXPECT_TRUE(bus.is_open());
}

// --- camera -----------------------------------------------------------------------------------

/// A camera serving gradient frames; the third grab reports the camera gone once.
class FakeCamera final : public drivers::Camera {
 public:
  explicit FakeCamera(std::atomic<int>& grabs) : grabs_(grabs) {}
  drivers::IoStatus start() override { return {}; }
  void stop() override {}
  drivers::IoStatus grab(drivers::CameraFrame& frame, std::chrono::milliseconds) override {
    const int k = grabs_.fetch_add(1);
    std::this_thread::sleep_for(5ms);
    if (k == 2) return drivers::IoStatus::Error(drivers::IoCode::kDisconnected, "fake", "gone");
    if (k > 5) return drivers::IoStatus::Error(drivers::IoCode::kTimeout, "fake", "idle");
    frame.image.create(48, 64, CV_16UC1);
    for (int r = 0; r < 48; ++r)
      for (int c = 0; c < 64; ++c)
        frame.image.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(c * 64);
    frame.frame_id = static_cast<std::uint64_t>(k);
    frame.time.host = drivers::host_time_now();
    frame.arrival_realtime_us = frame.time.host.realtime_us - 3000;
    return {};
  }
  drivers::IoStatus trigger() override { return {}; }
  drivers::CameraStats stats() const override { return {}; }
  const std::string& name() const override { return name_; }

 private:
  std::atomic<int>& grabs_;
  std::string name_ = "fake";
};

TEST(DeviceSource, CameraFramesBecomeImageEventsMetadataAndPngs) {
  const fs::path dir = fs::temp_directory_path() / ("navd_images_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  NavdConfig config;
  SensorConfig cam = sensor("camera", SensorType::kCameraGige);
  cam.camera.image_dir = dir.string();
  cam.latency_s = 0.01;
  config.sensors.push_back(cam);
  SensorHealthBoard board(config);
  MeasurementQueue queue(64);
  auto producer = queue.make_producer("camera");
  lcm::LCM lcm("memq://");
  LcmRawPublisher publisher(&lcm);
  RawSink sink(lcm);
  std::atomic<int> grabs{0};
  std::atomic<bool> stop{false};
  CameraContext context{config.sensors[0], 0, producer, &publisher, board.at(0), stop, {}};
  context.options.device.reconnect_initial = 10ms;
  const CameraOpener opener = [&](drivers::IoStatus&) -> std::unique_ptr<drivers::Camera> {
    return std::make_unique<FakeCamera>(grabs);
  };
  std::thread thread([&] { run_camera_device(opener, context); });
  ASSERT_TRUE(wait_until([&] { return grabs.load() > 7; }, 3s, nullptr));
  stop.store(true);
  thread.join();

  SensorHealth& h = board.at(0);
  EXPECT_EQ(h.messages.load(), 5u);  // grabs 0, 1, 3, 4, 5
  EXPECT_EQ(h.reconnects.load(), 1u);
  std::vector<Measurement> got;
  queue.pop_bulk(got, 100);
  ASSERT_EQ(got.size(), 5u);
  const auto& e = std::get<ImageEvent>(got[2]);
  EXPECT_EQ(e.frame_id, 3u);
  EXPECT_EQ(e.time.validity_us, e.time.host_monotonic_us - 3000 - 10'000);
  const cv::Mat png = cv::imread((dir / "000003.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(png.empty());
  EXPECT_EQ(png.depth(), CV_16U);
  EXPECT_EQ(png.at<std::uint16_t>(10, 63), 63 * 64);
  sink.drain();
  ASSERT_EQ(sink.images.size(), 5u);
  const navlcm::image_metadata_t& m = sink.images[2];
  EXPECT_EQ(m.frame_id, 3);
  EXPECT_EQ(m.file_path, "images/000003.png");
  EXPECT_EQ(m.time_of_validity_us, e.time.validity_us);
  EXPECT_EQ(m.width, 64);
  EXPECT_EQ(m.thumbnail_width, 64);  // frames narrower than the thumbnail stay as they are
  EXPECT_EQ(m.thumbnail_num_bytes, 64 * 48);
  EXPECT_EQ(m.thumbnail[63], 252);  // 63 * 64 = 4032 counts of 12 bits -> 252 of 8 bits
  fs::remove_all(dir);
}

TEST(DeviceSources, OneThreadPerDeviceSensorFromTheConfig) {
  Pty pty;
  ASSERT_GE(pty.master, 0);
  NavdConfig config;
  config.sensors.push_back(sensor("sim_dvl", SensorType::kDvlPd0));  // sim: no thread
  SensorConfig heading = sensor("heading", SensorType::kHeadingNmea);
  heading.transport = SerialTransport{pty.slave_path, 115200, Parity::kNone, FlowControl::kNone};
  config.sensors.push_back(heading);
  SensorConfig dvl = can_dvl();
  std::get<CanTransport>(dvl.transport).interface = "navd_no_such_can";
  config.sensors.push_back(dvl);
  SensorHealthBoard board(config);
  MeasurementQueue queue(256);
  std::atomic<bool> stop{false};
  DeviceSourcesOptions options;
  options.loop.read_timeout = 50ms;
  options.loop.reconnect_initial = 10ms;
  options.loop.reconnect_max = 50ms;
  DeviceSources sources(config, queue, nullptr, board, options);
  EXPECT_EQ(sources.start(stop), 2u);
  ASSERT_TRUE(wait_until([&] { return board.at(1).measurements.load() >= 3; }, 5s,
                         [&] { pty.send(hdt(33.0)); }));
  // The CAN bus cannot be opened here (no CAN in the kernel, or no such interface): the thread
  // keeps retrying with backoff and counts it.
  ASSERT_TRUE(wait_until([&] { return board.at(2).open_failures.load() >= 2; }, 3s, nullptr));
  const auto t0 = std::chrono::steady_clock::now();
  stop.store(true);
  sources.join();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);
  EXPECT_FALSE(board.at(0).active.load());
  EXPECT_TRUE(board.at(1).active.load());
  EXPECT_FALSE(board.at(2).connected.load());
  std::vector<Measurement> got;
  queue.pop_bulk(got, 1000);
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(time_of(got[0]).sensor_index, 1);
  const auto names = board.snapshot(0);
  ASSERT_EQ(names.size(), 2u);
  EXPECT_EQ(names[0].name, "heading");
  EXPECT_EQ(names[1].name, "dvl_can");
}

TEST(DeviceSources, GigeCameraThreadOnAravisInProcessFake) {
  arv_enable_interface("Fake");
  const fs::path dir = fs::temp_directory_path() / ("navd_gige_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  NavdConfig config;
  SensorConfig cam = sensor("camera", SensorType::kCameraGige);
  cam.transport = GigeTransport{"Fake_1"};
  cam.camera.fx_px = cam.camera.fy_px = 500.0;
  cam.camera.pixel_format = PixelFormat::kMono16;  // the stock fake has no Mono12
  cam.camera.trigger = Trigger::kFreeRun;
  cam.camera.frame_rate_hz = 20.0;
  cam.camera.image_dir = dir.string();
  config.sensors.push_back(cam);
  SensorHealthBoard board(config);
  MeasurementQueue queue(256);
  lcm::LCM lcm("memq://");
  RawSink sink(lcm);
  std::atomic<bool> stop{false};
  DeviceSources sources(config, queue, &lcm, board);
  ASSERT_EQ(sources.start(stop), 1u);
  const bool frames = wait_until([&] { return board.at(0).messages.load() >= 3; }, 10s, nullptr);
  stop.store(true);
  sources.join();
  ASSERT_TRUE(frames) << "no frames from the Aravis fake camera";
  std::vector<Measurement> got;
  queue.pop_bulk(got, 1000);
  ASSERT_EQ(got.size(), board.at(0).measurements.load());
  const auto& e = std::get<ImageEvent>(got.back());
  EXPECT_TRUE(fs::exists(dir / frame_png_name(e.frame_id))) << e.frame_id;
  sink.drain();
  ASSERT_EQ(sink.images.size(), got.size());
  EXPECT_EQ(sink.images.back().bits_per_pixel, 16);
  EXPECT_GT(sink.images.back().thumbnail_num_bytes, 0);
  EXPECT_EQ(sink.images.back().file_path, "images/" + frame_png_name(e.frame_id));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace nav::daemon
