// navd's device threads from the config (nav/daemon/sources/device_sources.h).
#include "nav/daemon/sources/device_sources.h"

#include <spdlog/spdlog.h>

#include <thread>

#include "nav/daemon/sources/camera_source.h"
#include "nav/daemon/system/realtime.h"
#include "nav/drivers/transports/gige_camera.h"
#include "nav/drivers/transports/serial_port.h"
#include "nav/drivers/transports/v4l2_camera.h"

namespace nav::daemon {

struct DeviceSources::Device {
  Device(const SensorConfig& s, std::uint16_t i, MeasurementQueue& queue)
      : sensor(s), index(i), producer(queue.make_producer(s.name)) {}
  const SensorConfig& sensor;
  std::uint16_t index;
  MeasurementQueue::Producer producer;
  std::unique_ptr<SensorDecoder> decoder;  ///< null for cameras
  std::atomic<bool> finished{false};       ///< its thread has returned from run()
};

namespace {

drivers::SerialOptions serial_options(const SerialTransport& t) {
  drivers::SerialOptions o;
  o.device = t.device;
  o.baud = t.baud;
  o.parity = t.parity == Parity::kEven  ? drivers::Parity::kEven
             : t.parity == Parity::kOdd ? drivers::Parity::kOdd
                                        : drivers::Parity::kNone;
  o.flow_control = t.flow == FlowControl::kRtsCts    ? drivers::FlowControl::kHardware
                   : t.flow == FlowControl::kXonXoff ? drivers::FlowControl::kSoftware
                                                     : drivers::FlowControl::kNone;
  return o;
}

drivers::GigeOptions gige_options(const GigeTransport& t, const CameraConfig& c) {
  drivers::GigeOptions o;
  o.camera_id = t.camera_id;
  switch (c.pixel_format) {
    case PixelFormat::kMono8:
      o.pixel_format = drivers::PixelFormat::kMono8;
      break;
    case PixelFormat::kMono16:
      o.pixel_format = drivers::PixelFormat::kMono16;
      break;
    default:  // mono12 (Bayer and RGB are refused by the camera's open() with a reason)
      o.pixel_format = drivers::PixelFormat::kMono12Packed;
      break;
  }
  o.trigger_mode = c.trigger == Trigger::kSoftware   ? drivers::TriggerMode::kSoftware
                   : c.trigger == Trigger::kHardware ? drivers::TriggerMode::kHardware
                                                     : drivers::TriggerMode::kFreeRun;
  o.frame_rate_hz = c.trigger == Trigger::kFreeRun ? c.frame_rate_hz : 0.0;
  return o;
}

CameraOpener camera_opener(const SensorConfig& sensor) {
  if (const auto* gige = std::get_if<GigeTransport>(&sensor.transport)) {
    const drivers::GigeOptions options = gige_options(*gige, sensor.camera);
    return [options](drivers::IoStatus& status) -> std::unique_ptr<drivers::Camera> {
      auto camera = std::make_unique<drivers::GigeCamera>(options);
      status = camera->open();
      return status.ok() ? std::move(camera) : nullptr;
    };
  }
  drivers::V4l2Options options;
  options.device = std::get<V4l2Transport>(sensor.transport).device;
  return [options](drivers::IoStatus& status) -> std::unique_ptr<drivers::Camera> {
    auto camera = std::make_unique<drivers::V4l2Camera>(options);
    status = camera->open();
    return status.ok() ? std::move(camera) : nullptr;
  };
}

}  // namespace

bool has_device(const SensorConfig& sensor) {
  return !std::holds_alternative<SimTransport>(sensor.transport);
}

DeviceSources::DeviceSources(const NavdConfig& config, MeasurementQueue& queue, lcm::LCM* lcm,
                             SensorHealthBoard& health, DeviceSourcesOptions options)
    : config_(config), queue_(queue), health_(health), options_(options), publisher_(lcm) {
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const SensorConfig& s = config.sensors[i];
    if (!has_device(s)) continue;
    auto device = std::make_unique<Device>(s, static_cast<std::uint16_t>(i), queue);
    if (has_sensor_decoder(s.type)) device->decoder = make_sensor_decoder(s, device->index);
    devices_.push_back(std::move(device));
  }
}

DeviceSources::~DeviceSources() { join(); }

std::size_t DeviceSources::start(const std::atomic<bool>& stop) {
  for (auto& device : devices_) {
    Device* d = device.get();
    threads_.emplace_back([this, d, &stop] {
      name_this_thread("navd-" + d->sensor.name);
      // Cameras keep normal scheduling: their frames carry the camera's or Aravis' stream
      // thread's time, and their threads convert and write whole images.
      if (!is_camera(d->sensor.type))
        realtime_.enter(d->sensor.name, config_.realtime.device_priority);
      run(*d, stop);
      d->finished.store(true);
    });
  }
  return threads_.size();
}

void DeviceSources::join() {
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
}

std::vector<std::string> DeviceSources::join_until(std::chrono::steady_clock::time_point deadline) {
  auto all_finished = [&] {
    for (std::size_t i = 0; i < threads_.size(); ++i) {
      if (threads_[i].joinable() && !devices_[i]->finished.load()) return false;
    }
    return true;
  };
  while (!all_finished() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::vector<std::string> abandoned;
  for (std::size_t i = 0; i < threads_.size(); ++i) {
    if (!threads_[i].joinable()) continue;
    if (devices_[i]->finished.load()) {
      threads_[i].join();
    } else {
      abandoned.push_back(devices_[i]->sensor.name);
      threads_[i].detach();
    }
  }
  return abandoned;
}

void DeviceSources::run(Device& d, const std::atomic<bool>& stop) {
  SensorHealth& health = health_.at(d.index);
  spdlog::info("sensor {}: {} device thread started", d.sensor.name, to_string(d.sensor.type));
  if (const auto* serial = std::get_if<SerialTransport>(&d.sensor.transport)) {
    drivers::SerialOptions o = serial_options(*serial);
    o.reconnect_initial = options_.loop.reconnect_initial;
    o.reconnect_max = options_.loop.reconnect_max;
    drivers::SerialPort port(o);
    DeviceLoopContext context{*d.decoder, d.producer, &publisher_, health, stop, options_.loop};
    run_byte_device(port, context);
  } else if (const auto* can = std::get_if<CanTransport>(&d.sensor.transport)) {
    const std::string interface = can->interface;
    const CanBusOpener open =
        [interface](drivers::IoStatus& status) -> std::unique_ptr<drivers::CanBus> {
      auto bus = std::make_unique<drivers::SocketCanBus>();
      status = bus->open_interface(interface);
      return status.ok() ? std::move(bus) : nullptr;
    };
    DeviceLoopContext context{*d.decoder, d.producer, &publisher_, health, stop, options_.loop};
    run_can_device(open, interface, context);
  } else {
    CameraContext context{d.sensor,
                          d.index,
                          d.producer,
                          &publisher_,
                          health,
                          stop,
                          CameraLoopOptions{options_.loop, options_.thumbnail_width_px}};
    run_camera_device(camera_opener(d.sensor), context);
  }
}

}  // namespace nav::daemon
