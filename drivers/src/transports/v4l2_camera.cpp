// V4L2 memory-mapped streaming capture (Linux "Video for Linux API", section "Streaming I/O
// (Memory Mapping)"): open, negotiate a 16-bit grey format, map buffers, STREAMON, DQBUF/QBUF.

#include "nav/drivers/transports/v4l2_camera.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

namespace nav::drivers {
namespace {

int xioctl(int fd, unsigned long request, void* arg) {
  int r = 0;
  do {
    r = ::ioctl(fd, request, arg);
  } while (r < 0 && errno == EINTR);
  return r;
}

}  // namespace

V4l2Camera::V4l2Camera(V4l2Options options)
    : options_(std::move(options)), options_status_(options_.validate()) {}

V4l2Camera::~V4l2Camera() { close(); }

IoStatus V4l2Camera::fail(int err, const std::string& what) {
  IoStatus s = IoStatus::FromErrno(err, options_.device, what);
  close();
  return s;
}

IoStatus V4l2Camera::open() {
  if (!options_status_.ok()) return options_status_;
  close();
  fd_ = ::open(options_.device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) return IoStatus::FromErrno(errno, options_.device, "open");
  v4l2_capability cap{};
  if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) != 0) {
    const int err = errno;
    close();
    return IoStatus::Error(IoCode::kUnsupported, options_.device,
                           "VIDIOC_QUERYCAP: not a V4L2 device", err);
  }
  const uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
  if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0 || (caps & V4L2_CAP_STREAMING) == 0) {
    close();
    return IoStatus::Error(IoCode::kUnsupported, options_.device,
                           "not a streaming video capture device");
  }
  IoStatus s = negotiate_format();
  if (s.ok()) s = map_buffers();
  return s;
}

IoStatus V4l2Camera::negotiate_format() {
  std::vector<uint32_t> offered;
  v4l2_fmtdesc desc{};
  desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  for (desc.index = 0; xioctl(fd_, VIDIOC_ENUM_FMT, &desc) == 0; ++desc.index)
    offered.push_back(desc.pixelformat);
  const auto chosen = choose_v4l2_format(offered, options_.formats);
  if (!chosen) {
    close();
    return IoStatus::Error(IoCode::kUnsupported, options_.device,
                           "offers none of the requested grey formats (" +
                               std::to_string(offered.size()) + " formats offered)");
  }
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<uint32_t>(options_.width);
  fmt.fmt.pix.height = static_cast<uint32_t>(options_.height);
  fmt.fmt.pix.pixelformat = *chosen;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(fd_, VIDIOC_S_FMT, &fmt) != 0) return fail(errno, "VIDIOC_S_FMT");
  // The driver may change the format: use what it actually set.
  const auto layout = v4l2_layout(fmt.fmt.pix.pixelformat, static_cast<int>(fmt.fmt.pix.width),
                                  static_cast<int>(fmt.fmt.pix.height), fmt.fmt.pix.bytesperline);
  if (!layout) {
    close();
    return IoStatus::Error(IoCode::kUnsupported, options_.device,
                           "driver changed the format to one we cannot read");
  }
  fourcc_ = fmt.fmt.pix.pixelformat;
  layout_ = *layout;
  return IoStatus::Ok();
}

IoStatus V4l2Camera::map_buffers() {
  v4l2_requestbuffers req{};
  req.count = static_cast<uint32_t>(options_.buffer_count);
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &req) != 0) return fail(errno, "VIDIOC_REQBUFS");
  if (req.count < 2) {
    close();
    return IoStatus::Error(IoCode::kUnsupported, options_.device,
                           "driver granted fewer than 2 buffers");
  }
  for (uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = i;
    if (xioctl(fd_, VIDIOC_QUERYBUF, &buf) != 0) return fail(errno, "VIDIOC_QUERYBUF");
    void* start =
        ::mmap(nullptr, buf.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buf.m.offset);
    if (start == MAP_FAILED) return fail(errno, "mmap");
    buffers_.push_back({start, buf.length});
  }
  return IoStatus::Ok();
}

void V4l2Camera::close() {
  stop();
  for (const Mapping& m : buffers_) ::munmap(m.start, m.length);
  buffers_.clear();
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

IoStatus V4l2Camera::start() {
  if (fd_ < 0)
    return IoStatus::Error(IoCode::kDisconnected, options_.device, "start: device not open");
  if (streaming_) return IoStatus::Ok();
  for (uint32_t i = 0; i < buffers_.size(); ++i) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = i;
    if (xioctl(fd_, VIDIOC_QBUF, &buf) != 0)
      return IoStatus::FromErrno(errno, options_.device, "VIDIOC_QBUF");
  }
  v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_STREAMON, &type) != 0)
    return IoStatus::FromErrno(errno, options_.device, "VIDIOC_STREAMON");
  ids_.reset();
  streaming_ = true;
  return IoStatus::Ok();
}

void V4l2Camera::stop() {
  if (!streaming_) return;
  streaming_ = false;
  v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  (void)xioctl(fd_, VIDIOC_STREAMOFF, &type);  // also dequeues every buffer
}

IoStatus V4l2Camera::trigger() {
  return IoStatus::Error(IoCode::kUnsupported, options_.device, "V4L2 has no software trigger");
}

IoStatus V4l2Camera::grab(CameraFrame& frame, std::chrono::milliseconds timeout) {
  if (!streaming_)
    return IoStatus::Error(IoCode::kInvalidArgument, options_.device, "grab: not streaming");
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd pfd{fd_, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, static_cast<int>(std::max<int64_t>(0, left.count())));
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) return IoStatus::FromErrno(errno, options_.device, "poll");
    if (ready == 0)
      return IoStatus::Error(IoCode::kTimeout, options_.device, "grab: no frame within timeout");
    if ((pfd.revents & POLLERR) != 0) {
      return IoStatus::Error(IoCode::kDisconnected, options_.device, "device error (unplugged?)");
    }
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_DQBUF, &buf) != 0) {
      if (errno == EAGAIN) continue;
      return IoStatus::FromErrno(errno, options_.device, "VIDIOC_DQBUF");  // ENODEV: unplugged
    }
    const HostTime received = host_time_now();
    const V4l2BufferInfo info{
        buf.sequence, (buf.flags & V4L2_BUF_FLAG_ERROR) != 0,
        (buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC,
        static_cast<int64_t>(buf.timestamp.tv_sec) * 1'000'000 + buf.timestamp.tv_usec,
        buf.bytesused};
    IoStatus s =
        IoStatus::Error(IoCode::kInvalidArgument, options_.device, "buffer index out of range");
    if (buf.index < buffers_.size()) {
      const Mapping& m = buffers_[buf.index];
      s = v4l2_buffer_to_frame({static_cast<const uint8_t*>(m.start), m.length}, info, layout_,
                               received, ids_, stats_, frame);
    }
    if (xioctl(fd_, VIDIOC_QBUF, &buf) != 0)
      return IoStatus::FromErrno(errno, options_.device, "VIDIOC_QBUF");
    if (s.ok()) return s;
    // Erroneous or short buffers are counted and skipped: wait for the next one.
  }
}

}  // namespace nav::drivers
