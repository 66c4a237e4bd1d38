// IoStatus: errno classification (which failures mean "device vanished", "busy", "no kernel
// support") and messages that name the device, the operation and the errno text.

#include <gtest/gtest.h>

#include <cerrno>

#include "nav/drivers/transports/io_status.h"

namespace nav::drivers {
namespace {

TEST(TransportIoStatus, ClassifiesErrnoValues) {
  EXPECT_EQ(IoStatus::FromErrno(EIO, "d", "read").code(), IoCode::kDisconnected);
  EXPECT_EQ(IoStatus::FromErrno(ENXIO, "d", "open").code(), IoCode::kDisconnected);
  EXPECT_EQ(IoStatus::FromErrno(ENODEV, "d", "ioctl").code(), IoCode::kDisconnected);
  EXPECT_EQ(IoStatus::FromErrno(ENOENT, "d", "open").code(), IoCode::kDisconnected);
  EXPECT_EQ(IoStatus::FromErrno(EBUSY, "d", "open").code(), IoCode::kBusy);
  EXPECT_EQ(IoStatus::FromErrno(EAFNOSUPPORT, "d", "socket").code(), IoCode::kUnsupported);
  EXPECT_EQ(IoStatus::FromErrno(EACCES, "d", "open").code(), IoCode::kSystemError);
}

TEST(TransportIoStatus, MessageNamesDeviceOperationAndErrnoText) {
  const IoStatus s = IoStatus::FromErrno(EACCES, "/dev/ttyUSB0", "open");
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.device(), "/dev/ttyUSB0");
  EXPECT_EQ(s.errno_value(), EACCES);
  EXPECT_EQ(s.message(), "/dev/ttyUSB0: open: Permission denied (system error)");
  const IoStatus t = IoStatus::Error(IoCode::kTimeout, "can0", "receive");
  EXPECT_EQ(t.message(), "can0: receive (timeout)");
  EXPECT_TRUE(IoStatus::Ok().ok());
  EXPECT_STREQ(to_string(IoCode::kDisconnected), "disconnected");
}

}  // namespace
}  // namespace nav::drivers
