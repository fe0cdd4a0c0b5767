// The VO configuration that matches a simulated stereo bench (drivers/stereo_sim): image size,
// camera intrinsics, baseline and the disparity range of the Mars-yard terrain. Shared by `qnav vo`,
// bench_vo and test_nav_vo; callers set the rest (corner cap, VME mode, matching, step limit).
#pragma once

#include "drivers/stereo_sim/mars_yard.hpp"
#include "nav/vo/stereo_vo.hpp"

namespace qnav::tools {

inline vo::VoConfig vo_config_for_bench(const sim::StereoBench& b) {
  vo::VoConfig c;
  c.max_width = b.width();
  c.max_height = b.height();
  c.camera.focal_px = b.focal_px();
  c.camera.cu_px = b.cu_px();
  c.camera.cv_px = b.cv_px();
  c.camera.baseline_m = b.baseline_m;
  c.stereo.min_disparity_px = 8;  // terrain at 0.55 .. 1.4 m: d = f b / Z = 12 .. 30 px
  c.stereo.max_disparity_px = 36;
  c.stereo.disparity_sigma_px = 0.15f;
  return c;
}

}  // namespace qnav::tools
