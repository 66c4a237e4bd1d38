// FakeGigeCamera: Aravis' GigE Vision fake on lo serving the dive's frames on the player's
// trigger; see fake_gige_camera.h.
#include "fake_gige_camera.h"

#include <arv.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <vector>

#include "nav/daemon/system/host_clock.h"
#include "nav/drivers/transports/mono_unpack.h"

namespace nav::hil {
namespace {

/// Longest the fill callback holds the fake's thread (its GVCP answers wait meanwhile; Aravis'
/// heartbeat timeout is 3 s).
constexpr std::int64_t kMaxHoldUs = 1'000'000;

void sleep_until_monotonic_us(std::int64_t until_us) {
  const std::int64_t now = daemon::monotonic_us();
  until_us = std::min(until_us, now + kMaxHoldUs);
  if (until_us <= now) return;
  const timespec ts{static_cast<time_t>(until_us / 1'000'000),
                    static_cast<long>((until_us % 1'000'000) * 1000)};
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

/// Inserts `entries` before the first `<pValue>register</pValue>` of the XML; false if absent.
bool add_enum_entries(std::string& xml, const std::string& register_name,
                      const std::string& entries) {
  const std::string anchor = "<pValue>" + register_name + "</pValue>";
  const auto at = xml.find(anchor);
  if (at == std::string::npos) return false;
  xml.insert(at, entries);
  return true;
}

/// The stock fake's GenICam XML with Mono12 / Mono12Packed pixel formats and a Line1 trigger
/// source equal to Software (fake_gige_camera.h); "" and `why` on failure.
std::string hil_genicam_xml(std::string& why) {
  ArvFakeCamera* probe = arv_fake_camera_new("probe");
  if (probe == nullptr) {
    why = "arv_fake_camera_new failed";
    return {};
  }
  size_t size = 0;
  const char* text = arv_fake_camera_get_genicam_xml(probe, &size);
  std::string xml = text != nullptr ? std::string(text, size) : std::string();
  g_object_unref(probe);
  const bool ok =
      add_enum_entries(xml, "PixelFormatRegister",
                       "<EnumEntry Name=\"Mono12\" NameSpace=\"Standard\"><Value>17825797</Value>"
                       "</EnumEntry>\n<EnumEntry Name=\"Mono12Packed\" NameSpace=\"Standard\">"
                       "<Value>17563654</Value></EnumEntry>\n") &&
      add_enum_entries(xml, "TriggerSourceRegister",
                       "<EnumEntry Name=\"Line1\" NameSpace=\"Standard\"><Value>1</Value>"
                       "</EnumEntry>\n");
  if (!ok) {
    why = "the stock fake's GenICam XML has no PixelFormat / TriggerSource register to extend";
    return {};
  }
  return xml;
}

ArvFakeCamera* fake_of(void* gv_camera) {
  return arv_gv_fake_camera_get_fake_camera(static_cast<ArvGvFakeCamera*>(gv_camera));
}

}  // namespace

FakeGigeCamera::~FakeGigeCamera() {
  if (camera_ != nullptr) g_object_unref(static_cast<ArvGvFakeCamera*>(camera_));
  std::error_code ignored;
  if (!genicam_path_.empty()) std::filesystem::remove(genicam_path_, ignored);
}

std::string FakeGigeCamera::start(const std::string& serial, int width_px, int height_px) {
  if (width_px <= 0 || height_px <= 0 || width_px > ARV_FAKE_CAMERA_SENSOR_WIDTH ||
      height_px > ARV_FAKE_CAMERA_SENSOR_HEIGHT) {
    return "frame " + std::to_string(width_px) + " x " + std::to_string(height_px) +
           " px does not fit the fake's 2048 x 2048 sensor";
  }
  serial_ = serial;
  width_px_ = width_px;
  height_px_ = height_px;
  std::string why;
  const std::string xml = hil_genicam_xml(why);
  if (xml.empty()) return why;
  genicam_path_ = std::filesystem::temp_directory_path() /
                  ("navhil_fake_camera_" + std::to_string(::getpid()) + "_" + serial + ".xml");
  if (!(std::ofstream(genicam_path_) << xml)) return genicam_path_.string() + ": cannot write";
  ArvGvFakeCamera* camera =
      arv_gv_fake_camera_new_full("lo", serial.c_str(), genicam_path_.c_str());
  if (camera == nullptr) return "arv_gv_fake_camera_new_full(\"lo\") failed";
  if (!arv_gv_fake_camera_is_running(camera)) {
    g_object_unref(camera);
    return "Aravis' fake GigE camera cannot listen on lo (GVCP port 3956 taken or no lo)";
  }
  camera_ = camera;
  ArvFakeCamera* fake = fake_of(camera_);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH, width_px);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT, height_px);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT,
                                 ARV_PIXEL_FORMAT_MONO_12_PACKED);
  arv_fake_camera_set_fill_pattern(fake, &fill, this);
  return {};
}

void FakeGigeCamera::vanish() {
  if (camera_ == nullptr) return;
  g_object_unref(static_cast<ArvGvFakeCamera*>(camera_));  // joins the fake's thread
  camera_ = nullptr;
  std::lock_guard lock(mutex_);
  pending_ = false;
  pending_image_ = cv::Mat();
}

std::string FakeGigeCamera::reappear() {
  if (camera_ != nullptr) return {};
  if (serial_.empty()) return "the fake GigE camera was never started";
  return start(serial_, width_px_, height_px_);
}

void FakeGigeCamera::fire(cv::Mat image, std::int64_t due_monotonic_us) {
  if (camera_ == nullptr) return;
  {
    std::lock_guard lock(mutex_);
    if (pending_) ++stats_.not_taken;
    pending_ = true;
    pending_image_ = std::move(image);
    pending_due_us_ = due_monotonic_us;
    ++stats_.fired;
  }
  arv_fake_camera_write_register(fake_of(camera_), ARV_FAKE_CAMERA_REGISTER_TRIGGER_SOFTWARE, 1);
}

bool FakeGigeCamera::idle() const {
  std::lock_guard lock(mutex_);
  return !pending_;
}

FakeCameraStats FakeGigeCamera::stats() const {
  std::lock_guard lock(mutex_);
  FakeCameraStats s = stats_;
  s.mean_late_s = s.sent > 0 ? late_sum_s_ / static_cast<double>(s.sent) : 0.0;
  return s;
}

std::uint16_t FakeGigeCamera::pattern_value(int x, int y, std::int64_t n) {
  return static_cast<std::uint16_t>((x * 7 + y * 13 + n * 101) & 0xfff);
}

void FakeGigeCamera::fill(_ArvBuffer* buffer, void* self, std::uint32_t, std::uint32_t,
                          std::uint32_t pixel_format) {
  static_cast<FakeGigeCamera*>(self)->fill_buffer(buffer, pixel_format);
}

void FakeGigeCamera::fill_buffer(_ArvBuffer* buffer, std::uint32_t pixel_format) {
  cv::Mat image;
  std::int64_t due_us = 0;
  bool asked = false;
  std::int64_t pattern_n = 0;
  {
    std::lock_guard lock(mutex_);
    asked = pending_;
    pending_ = false;
    image = std::move(pending_image_);
    pending_image_ = cv::Mat();
    due_us = pending_due_us_;
    if (image.empty()) pattern_n = pattern_frames_++;
    if (!asked) ++stats_.unasked;
  }
  const auto format = drivers::pixel_format_from_pfnc(pixel_format);
  if (!format) return;
  const drivers::ImageLayout layout{arv_buffer_get_image_width(buffer),
                                    arv_buffer_get_image_height(buffer), *format, 0};
  cv::Mat frame(layout.height, layout.width, CV_16UC1, cv::Scalar(0));
  if (!image.empty() && image.type() == CV_16UC1) {
    const cv::Rect common(0, 0, std::min(image.cols, frame.cols), std::min(image.rows, frame.rows));
    image(common).copyTo(frame(common));
  } else {
    for (int y = 0; y < frame.rows; ++y)
      for (int x = 0; x < frame.cols; ++x)
        frame.at<std::uint16_t>(y, x) = pattern_value(x, y, pattern_n);
  }
  if (*format == drivers::PixelFormat::kMono8) frame.convertTo(frame, CV_8U, 1.0 / 16.0);
  const std::vector<std::uint8_t> bytes = drivers::pack_mono(frame, layout);
  if (asked) sleep_until_monotonic_us(due_us);  // the frame leaves at its due time
  size_t ignored = 0;
  auto* data = static_cast<std::uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, &ignored)));
  const size_t capacity = arv_fake_camera_get_payload(fake_of(camera_));
  if (data != nullptr) std::memcpy(data, bytes.data(), std::min(capacity, bytes.size()));
  if (!asked) return;
  const double late_s = (daemon::monotonic_us() - due_us) * 1e-6;
  std::lock_guard lock(mutex_);
  ++stats_.sent;
  if (!image.empty()) ++stats_.from_image;
  stats_.max_late_s = std::max(stats_.max_late_s, late_s);
  late_sum_s_ += late_s;
}

}  // namespace nav::hil
