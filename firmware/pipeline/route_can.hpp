// The repeat step as qnav's CAN outputs: one localiser step -> QNAV_ROUTE_GUIDANCE + QNAV_ROUTE_STATUS
// (docs/qnav.dbc), values clamped to the DBC ranges, non-finite values sent as 0 (the sigma as
// "unknown"). DistToNext: the next node in the direction of travel is one node spacing ahead of the
// node the offsets refer to. Header-only, O(1), no heap. Used by `qnav route follow`; qnavd's nav
// worker calls it too. The ranges come from the DBC table (drivers/qnavcan clamp_to_signal).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "drivers/qnavcan/messages.hpp"
#include "nav/route/route_localiser.hpp"

namespace qnav::pipeline {

inline drivers::qnavcan::GuidanceState route_status_to_wire(route::GuidanceStatus s) noexcept {
  using W = drivers::qnavcan::GuidanceState;
  switch (s) {
    case route::GuidanceStatus::kTracking: return W::kTracking;
    case route::GuidanceStatus::kHoldCourse: return W::kHoldCourse;
    case route::GuidanceStatus::kDeadReckoned: return W::kDeadReckoned;
    case route::GuidanceStatus::kRouteEnd: return W::kRouteEnd;
  }
  return W::kHoldCourse;
}
inline drivers::qnavcan::SideOfRoute route_side_to_wire(route::RouteSide s) noexcept {
  using W = drivers::qnavcan::SideOfRoute;
  switch (s) {
    case route::RouteSide::kPort: return W::kPort;
    case route::RouteSide::kOnRoute: return W::kOnRoute;
    case route::RouteSide::kStarboard: return W::kStarboard;
    case route::RouteSide::kUnknown: return W::kUnknown;
  }
  return W::kUnknown;
}

inline void route_can_messages(const route::LocaliserStep& st, double node_spacing_m, std::uint32_t tile_seq,
                               drivers::qnavcan::RouteGuidance& guidance,
                               drivers::qnavcan::RouteStatus& status) noexcept {
  namespace qc = drivers::qnavcan;
  const route::GuidanceOutput& g = st.guidance;
  guidance.cross_track_m = qc::clamp_to_signal(qc::kIdRouteGuidance, "CrossTrack", g.cross_track_m);
  guidance.heading_error_rad = qc::clamp_to_signal(qc::kIdRouteGuidance, "HeadingError", g.heading_error_rad);
  guidance.dist_to_next_m = qc::clamp_to_signal(qc::kIdRouteGuidance, "DistToNext", node_spacing_m - g.along_track_m);
  guidance.target_node = static_cast<std::uint16_t>(std::min<std::uint32_t>(g.node, 65535));
  status.status = route_status_to_wire(g.status);
  status.side = route_side_to_wire(g.side);
  status.cross_track_sigma_m =
      std::isfinite(g.cross_track_sigma_m) ? g.cross_track_sigma_m : drivers::qnavcan::kCrossTrackSigmaMaxM;
  status.estimate_node = static_cast<std::uint16_t>(std::min<std::uint32_t>(st.estimate, 65535));
  status.tile_seq = static_cast<std::uint16_t>(tile_seq & 0xFFFF);
}

}  // namespace qnav::pipeline
