#pragma once
// The navd config of a hardware-in-the-loop playback (dive_player.h): the dive's config.yaml
// with each sensor's transport pointing at what the player writes to.

#include <filesystem>
#include <string>
#include <vector>

#include "nav/hil/dive_player.h"

namespace nav::hil {

/// `dive_config_yaml` is the text of the dive's config.yaml, found in `dive_config_dir`
/// (relative CAN signal tables become absolute paths there). Throws std::runtime_error if the
/// text is not a YAML map with a `sensors` list. The camera the fake GigE camera plays is
/// triggered on Line1 by the player (`trigger: hardware`), and navd writes the frames it gets
/// to `camera_image_dir` (empty: the dive config's `image_dir`, if any).
std::string hil_navd_config_yaml(const std::string& dive_config_yaml,
                                 const std::filesystem::path& dive_config_dir,
                                 const std::vector<PlayedSensor>& sensors,
                                 const std::string& lcm_url,
                                 const std::filesystem::path& camera_image_dir = {});

}  // namespace nav::hil
