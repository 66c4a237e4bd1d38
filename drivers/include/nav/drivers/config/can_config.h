#pragma once
// CAN signal tables from YAML (yaml-cpp): the DBC model of can_signals.h written as a config
// file, so vendor-specific DVL and gyro layouts need no code. Schema (every key documented in
// config/can/dvl_fog_example.yaml):
//
//   messages:
//     - name: dvl_velocity        # unique
//       id: 0x200                 # hex (0x...) or decimal; 11 bits, or 29 with extended: true
//       extended: false           # optional, default false
//       dlc: 8                    # data length 0..8; frames of another length are malformed
//       multiplexer: beam_index   # optional: name of the multiplexer switch signal (DBC M)
//       time_from: dvl_time       # optional: the (earlier) message whose time signal dates
//       time_match: ping_seq      #   this one, matched by this signal present in both
//       signals:
//         - name: v_x_mps
//           start_bit: 0          # DBC numbering: Intel -> LSB, Motorola -> MSB (sawtooth)
//           length: 16            # 1..64
//           byte_order: intel     # intel | little_endian | motorola | big_endian
//           signed: true          # optional, default false (two's complement)
//           scale: 0.1            # optional, default 1 (DBC factor)
//           offset: 0             # optional, default 0
//           unit: mm/s            # optional, default "" (dimensionless); converted to SI
//           min: -5000            # optional physical range in `unit` (before SI conversion)
//           max: 5000             # min: 0 with max: 0 means no range (DBC's [0|0])
//           invalid: 0x8000       # optional raw pattern meaning "no value" (negative ok if signed)
//           multiplexer_value: 1  # optional, DBC m1: present only when the switch equals 1
//           time_of_validity: true  # optional: sensor time counter of the message
//
// Errors name the file, the key path and the reason, e.g.
// "dvl.yaml: messages[2].signals[0].length: 0 is not in 1..64"; unknown keys are errors too
// (a misspelt optional key would otherwise be silently ignored).

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "nav/drivers/codecs/can_signals.h"

namespace nav::drivers {

struct CanConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct CanConfig {
  std::vector<CanMessageSpec> messages;  ///< passes validate_can_messages
};

/// Parses YAML text; `source` names it in errors (a file name). Throws CanConfigError.
CanConfig parse_can_config(const std::string& yaml_text, const std::string& source = "<string>");
/// Reads and parses a file. Throws CanConfigError (also when the file cannot be read).
CanConfig load_can_config_file(const std::string& path);

}  // namespace nav::drivers
