#pragma once
// Foxglove WebSocket protocol v1 ("foxglove.websocket.v1", JSON encoding) pieces: the server's
// text messages (serverInfo, advertise, status), the binary message-data frame, and navd's
// messages as Foxglove schemas: foxglove.PoseInFrame for the solution, foxglove.SceneUpdate
// with ellipsoids (3-sigma bounds) and lines (camera links), foxglove.Log for navd's status.
// Protocol: https://github.com/foxglove/ws-protocol/blob/main/docs/spec.md. Frame "ned":
// x north, y east, z down, as navd's world frame.
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nav/daemon/topside/lcm_json.h"

namespace nav::daemon::topside {

inline constexpr const char* kFoxgloveSubprotocol = "foxglove.websocket.v1";
inline constexpr const char* kFoxgloveFrameId = "ned";

/// One advertised channel (all JSON-encoded; schema is a JSON Schema text).
struct FoxgloveChannel {
  std::uint32_t id = 0;
  std::string topic;
  std::string schema_name;
  std::string schema;
};

/// The channels navtool topside advertises (fixed ids, 1..N), see foxglove.cpp.
const std::vector<FoxgloveChannel>& foxglove_channels();
/// The id of the advertised channel with `topic`; throws std::out_of_range if none.
std::uint32_t foxglove_channel_id(const std::string& topic);

nlohmann::json server_info_message(const std::string& name);
nlohmann::json advertise_message(const std::vector<FoxgloveChannel>& channels);
/// level 0 info, 1 warning, 2 error.
nlohmann::json status_message(int level, const std::string& message);

/// Binary server message: opcode 0x01, subscription id u32 LE, log time u64 LE (ns), payload.
std::string message_data_frame(std::uint32_t subscription_id, std::uint64_t log_time_ns,
                               const std::string& payload);

/// {sec, nsec} of a time in microseconds.
nlohmann::json foxglove_time(std::int64_t time_us);

/// foxglove.PoseInFrame of the solution: position p_world_m and the orientation of the
/// roll-pitch-heading (Z-Y-X) rotation from body to world.
nlohmann::json pose_in_frame(const navlcm::nav_solution_t& m);

/// foxglove.SceneUpdate with one entity "state/<id>" per bound: a sphere primitive scaled to the
/// 3-sigma ellipsoid of the position block of the conservative bound.
nlohmann::json bounds_scene_update(const std::vector<navlcm::delayed_state_bound_t>& states);

/// foxglove.SceneUpdate with one entity "link/<i>-<j>": a line between the two states' mean
/// positions (from `positions`, id -> x y z); green temporal (j follows i), orange loop-closing,
/// grey rejected. Empty update if either position is unknown.
nlohmann::json link_scene_update(const navlcm::camera_link_t& link,
                                 const std::map<std::int64_t, std::array<double, 3>>& positions,
                                 bool temporal);

/// foxglove.Log of navd's status line (level INFO, WARNING when any sensor is disconnected).
nlohmann::json health_log(const navlcm::health_t& m);

}  // namespace nav::daemon::topside
