#include "test/timing/freestanding/workload.hpp"

#include "test/timing/canned.hpp"

namespace qnav::timing {

Status run_freestanding_workload(FreestandingResult& out) {
  out = FreestandingResult{};
  {
    CannedVo vo;
    QNAV_RETURN_IF_ERROR(vo.init());
    vo.vo_reference(0);
    out.vo_step = vo.vo_step(0);
    out.stage[0] = vo.harris(0);
    out.stage[1] = vo.harris(1);
    out.stage[2] = vo.remap(0);
    out.stage[3] = vo.stereo(0);
    out.stage[4] = vo.match_fc();
    out.stage[5] = vo.motion_6d();
    out.stage[6] = vo.motion_3d();
  }
  {
    CannedRoute route;
    QNAV_RETURN_IF_ERROR(route.init());
    route.route_restart();
    out.route_update = route.route_update(0);
  }
  {
    CannedSonar sonar;
    QNAV_RETURN_IF_ERROR(sonar.init());
    Hash x;
    for (int k = 0; k < CannedSonar::kPings; ++k) x.add(sonar.xtf_decode(k));
    out.xtf_decode = x.value();
  }
  Hash h;
  h.add(out.vo_step);
  h.add(out.route_update);
  h.add(out.xtf_decode);
  out.all = h.value();
  if (out.vo_step == 0) return Status(StatusCode::kNotReady, "vo_step failed on its canned input");
  if (out.route_update == 0) return Status(StatusCode::kNotReady, "route_update failed on its canned input");
  return Status::ok();
}

}  // namespace qnav::timing
