// VoPriorConfig: how VoOdometry forms the translation prior when the caller gives no odometry. Its own
// header so that vo_defaults.hpp (also compiled freestanding for LEON3, test/timing/freestanding) can
// define the presets' priors without pulling in VoOdometry.
#pragma once

namespace qnav::pipeline {

struct VoPriorConfig {
  bool zero_motion = false;      // the rig barely moves (a hover): zero motion within zero_sigma_m
  double zero_sigma_m = 0.02;
  double first_sigma_m = 0.0;    // before the first visual step: zero within this (0: none, the matcher's own gate)
};

}  // namespace qnav::pipeline
