#pragma once
// The cameras of the vision tests and benchmarks: the survey simulator's 1280x1024 camera
// (config/sim.yaml: fx = fy = 1000 px, principal point at the centre, no distortion) and the
// calibrated Sparus II camera of data/images/sparus (data/README.md, OpenCV model, pixels).
#include "nav/vision/vision_types.h"

namespace nav::vision::test {

inline CameraIntrinsics sim_camera() {
  CameraIntrinsics c;
  c.fx_px = c.fy_px = 1000.0;
  c.cx_px = 640.0;
  c.cy_px = 512.0;
  c.width_px = 1280;
  c.height_px = 1024;
  return c;
}

inline CameraIntrinsics sparus_camera() {
  CameraIntrinsics c;
  c.fx_px = 405.6384738851233;
  c.fy_px = 405.588335378204;
  c.cx_px = 189.9054317917407;
  c.cy_px = 139.9149578253755;
  c.k1 = -0.3670656233416921;
  c.k2 = 0.203001968694465;
  c.p1 = 0.003336917744124004;
  c.p2 = -0.000487426354679637;
  c.width_px = 384;
  c.height_px = 288;
  return c;
}

}  // namespace nav::vision::test
