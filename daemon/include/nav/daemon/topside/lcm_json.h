#pragma once
// navd's LCM messages as JSON for the topside web page: one converter per navlcm type. Field
// names and units are those of lcmtypes/*.lcm (x north, y east, z down in metres; angles in
// radians; times in microseconds), plus a few derived display values named with their units
// (depth_m, speed_mps, sigma_xy_m, ellipse_3sigma). Pure functions: no I/O, no clocks.
#include <navlcm/bounds_snapshot_t.hpp>
#include <navlcm/camera_link_t.hpp>
#include <navlcm/delayed_state_bound_t.hpp>
#include <navlcm/health_t.hpp>
#include <navlcm/image_metadata_t.hpp>
#include <navlcm/link_proposal_t.hpp>
#include <navlcm/nav_solution_t.hpp>
#include <nlohmann/json.hpp>

namespace nav::daemon::topside {

/// Pose, velocity, 1-sigma horizontal accuracy (semi-major axis of the x-y marginal), the
/// delayed-state and link counts, filter_status (0 ok, 1 degraded, 2 initialising).
nlohmann::json to_json(const navlcm::nav_solution_t& m);

/// One sensor's health row, its last aiding updates as "last": [{...}, ...].
nlohmann::json to_json(const navlcm::sensor_health_t& m);
nlohmann::json to_json(const navlcm::aid_source_t& m);

/// Per-sensor rows plus queue depth, CG residual, CPU and memory of navd.
nlohmann::json to_json(const navlcm::health_t& m);

/// One delayed state: its mean position and the x-y marginal of its conservative bound as a
/// 3-sigma ellipse (see ellipse.h).
nlohmann::json to_json(const navlcm::delayed_state_bound_t& m);
nlohmann::json to_json(const navlcm::bounds_snapshot_t& m);

/// A camera link between two delayed states, accepted or rejected with the reason.
nlohmann::json to_json(const navlcm::camera_link_t& m);
nlohmann::json to_json(const navlcm::link_proposal_t& m);

/// Image metadata without the thumbnail bytes (their count is kept).
nlohmann::json to_json(const navlcm::image_metadata_t& m);

}  // namespace nav::daemon::topside
