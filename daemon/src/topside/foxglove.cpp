// Foxglove ws-protocol v1 JSON messages and navd's messages in Foxglove's schemas
// (https://docs.foxglove.dev/docs/visualization/message-schemas: PoseInFrame, SceneUpdate, Log).
#include "nav/daemon/topside/foxglove.h"

#include <cmath>
#include <stdexcept>

#include "nav/daemon/topside/ellipse.h"

namespace nav::daemon::topside {
namespace {

// Minimal JSON Schemas: Foxglove needs a schema name to pick a panel; the JSON is self-describing.
std::string object_schema(const char* title) {
  return nlohmann::json{{"title", title}, {"type", "object"}}.dump();
}

nlohmann::json vec3(double x, double y, double z) { return {{"x", x}, {"y", y}, {"z", z}}; }

nlohmann::json color(double r, double g, double b, double a) {
  return {{"r", r}, {"g", g}, {"b", b}, {"a", a}};
}

nlohmann::json identity_pose(double x, double y, double z) {
  return {{"position", vec3(x, y, z)}, {"orientation", {{"x", 0}, {"y", 0}, {"z", 0}, {"w", 1}}}};
}

/// An entity with no primitives; callers fill one list.
nlohmann::json entity(std::int64_t time_us, const std::string& id) {
  nlohmann::json e = {{"timestamp", foxglove_time(time_us)},
                      {"frame_id", kFoxgloveFrameId},
                      {"id", id},
                      {"lifetime", {{"sec", 0}, {"nsec", 0}}},
                      {"frame_locked", false},
                      {"metadata", nlohmann::json::array()}};
  for (const char* list : {"arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts",
                           "models"}) {
    e[list] = nlohmann::json::array();
  }
  return e;
}

}  // namespace

const std::vector<FoxgloveChannel>& foxglove_channels() {
  static const std::vector<FoxgloveChannel> channels = {
      {1, "/navd/pose", "foxglove.PoseInFrame", object_schema("foxglove.PoseInFrame")},
      {2, "/navd/bounds", "foxglove.SceneUpdate", object_schema("foxglove.SceneUpdate")},
      {3, "/navd/links", "foxglove.SceneUpdate", object_schema("foxglove.SceneUpdate")},
      {4, "/navd/log", "foxglove.Log", object_schema("foxglove.Log")},
      {5, "NAVD_SOLUTION", "navlcm.nav_solution_t", object_schema("navlcm.nav_solution_t")},
      {6, "NAVD_HEALTH", "navlcm.health_t", object_schema("navlcm.health_t")},
      {7, "NAVD_CAMERA_LINKS", "navlcm.camera_link_t", object_schema("navlcm.camera_link_t")},
      {8, "NAV_LINK_PROPOSAL", "navlcm.link_proposal_t", object_schema("navlcm.link_proposal_t")},
  };
  return channels;
}

std::uint32_t foxglove_channel_id(const std::string& topic) {
  for (const FoxgloveChannel& c : foxglove_channels()) {
    if (c.topic == topic) return c.id;
  }
  throw std::out_of_range("no Foxglove channel advertised for topic '" + topic + "'");
}

nlohmann::json server_info_message(const std::string& name) {
  return {{"op", "serverInfo"},
          {"name", name},
          {"capabilities", nlohmann::json::array()},
          {"supportedEncodings", nlohmann::json::array({"json"})},
          {"metadata", nlohmann::json::object()},
          {"sessionId", name}};
}

nlohmann::json advertise_message(const std::vector<FoxgloveChannel>& channels) {
  nlohmann::json list = nlohmann::json::array();
  for (const FoxgloveChannel& c : channels) {
    list.push_back({{"id", c.id},
                    {"topic", c.topic},
                    {"encoding", "json"},
                    {"schemaName", c.schema_name},
                    {"schema", c.schema},
                    {"schemaEncoding", "jsonschema"}});
  }
  return {{"op", "advertise"}, {"channels", std::move(list)}};
}

nlohmann::json status_message(int level, const std::string& message) {
  return {{"op", "status"}, {"level", level}, {"message", message}};
}

std::string message_data_frame(std::uint32_t subscription_id, std::uint64_t log_time_ns,
                               const std::string& payload) {
  std::string frame(13 + payload.size(), '\0');
  frame[0] = static_cast<char>(0x01);
  for (int i = 0; i < 4; ++i) frame[1 + i] = static_cast<char>((subscription_id >> (8 * i)) & 0xFF);
  for (int i = 0; i < 8; ++i) frame[5 + i] = static_cast<char>((log_time_ns >> (8 * i)) & 0xFF);
  frame.replace(13, payload.size(), payload);
  return frame;
}

nlohmann::json foxglove_time(std::int64_t time_us) {
  const std::int64_t sec = time_us >= 0 ? time_us / 1'000'000 : (time_us - 999'999) / 1'000'000;
  return {{"sec", sec}, {"nsec", (time_us - sec * 1'000'000) * 1000}};
}

nlohmann::json pose_in_frame(const navlcm::nav_solution_t& m) {
  // q = qz(heading) * qy(pitch) * qx(roll), the body-to-NED rotation of navd's Euler angles.
  const double hr = 0.5 * m.rph_rad[0], hp = 0.5 * m.rph_rad[1], hy = 0.5 * m.rph_rad[2];
  const double cr = std::cos(hr), sr = std::sin(hr), cp = std::cos(hp), sp = std::sin(hp);
  const double cy = std::cos(hy), sy = std::sin(hy);
  const nlohmann::json q = {{"x", sr * cp * cy - cr * sp * sy},
                            {"y", cr * sp * cy + sr * cp * sy},
                            {"z", cr * cp * sy - sr * sp * cy},
                            {"w", cr * cp * cy + sr * sp * sy}};
  return {{"timestamp", foxglove_time(m.utime)},
          {"frame_id", kFoxgloveFrameId},
          {"pose", {{"position", vec3(m.p_world_m[0], m.p_world_m[1], m.p_world_m[2])},
                    {"orientation", q}}}};
}

nlohmann::json bounds_scene_update(const std::vector<navlcm::delayed_state_bound_t>& states) {
  nlohmann::json entities = nlohmann::json::array();
  for (const auto& s : states) {
    const Ellipsoid3 ell = covariance_ellipsoid(position_block(s.bound_covariance), 3.0);
    nlohmann::json e = entity(s.utime, "state/" + std::to_string(s.state_id));
    e["spheres"].push_back(
        {{"pose",
          {{"position", vec3(s.mean_pose[0], s.mean_pose[1], s.mean_pose[2])},
           {"orientation",
            {{"x", ell.q_xyzw[0]}, {"y", ell.q_xyzw[1]}, {"z", ell.q_xyzw[2]}, {"w", ell.q_xyzw[3]}}}}},
         {"size", vec3(ell.size_m[0], ell.size_m[1], ell.size_m[2])},
         {"color", color(0.2, 0.5, 1.0, 0.35)}});
    entities.push_back(std::move(e));
  }
  return {{"deletions", nlohmann::json::array()}, {"entities", std::move(entities)}};
}

nlohmann::json link_scene_update(const navlcm::camera_link_t& link,
                                 const std::map<std::int64_t, std::array<double, 3>>& positions,
                                 bool temporal) {
  nlohmann::json update = {{"deletions", nlohmann::json::array()},
                           {"entities", nlohmann::json::array()}};
  const auto i = positions.find(link.state_id_i);
  const auto j = positions.find(link.state_id_j);
  if (i == positions.end() || j == positions.end()) return update;
  nlohmann::json e = entity(link.utime, "link/" + std::to_string(link.state_id_i) + "-" +
                                            std::to_string(link.state_id_j));
  const nlohmann::json c = !link.accepted ? color(0.6, 0.6, 0.6, 0.8)
                           : temporal     ? color(0.2, 0.8, 0.3, 1.0)
                                          : color(1.0, 0.55, 0.0, 1.0);
  e["lines"].push_back({{"type", 2},  // LINE_LIST
                        {"pose", identity_pose(0, 0, 0)},
                        {"thickness", 0.05},
                        {"scale_invariant", false},
                        {"points", {vec3(i->second[0], i->second[1], i->second[2]),
                                    vec3(j->second[0], j->second[1], j->second[2])}},
                        {"color", c},
                        {"colors", nlohmann::json::array()},
                        {"indices", nlohmann::json::array()}});
  update["entities"].push_back(std::move(e));
  return update;
}

nlohmann::json health_log(const navlcm::health_t& m) {
  bool all_connected = true;
  for (const auto& s : m.sensors) all_connected = all_connected && s.connected;
  return {{"timestamp", foxglove_time(m.utime)},
          {"level", all_connected ? 2 : 3},  // INFO, WARNING
          {"message", m.status},
          {"name", "navd"},
          {"file", ""},
          {"line", 0}};
}

}  // namespace nav::daemon::topside
