#pragma once
// CRC-32 (IEEE 802.3) of the checkpoint files: the implementation lives in nav_core
// (nav/core/serialization/crc32.h), shared with the map section container.

#include "nav/core/serialization/crc32.h"

namespace nav::daemon {

using nav::core::crc32;
using nav::core::crc32_update;

}  // namespace nav::daemon
