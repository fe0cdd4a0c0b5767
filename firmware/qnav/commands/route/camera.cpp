// qnav route: camera, teach and repeat on a downward camera (split from route.cpp; what the files share: route_cmd.hpp).
#include "firmware/qnav/commands/route/route_cmd.hpp"

#include "firmware/pipeline/camera_tile_pipeline.hpp"

namespace route_cmd {

// ---------------------------------------------------------------------------------------------------
// qnav route camera: the same route teach and repeat on a downward camera (SensorKind::kCamera).
namespace {

// A downward camera 0.8 m above the synthetic Mars yard (the VO bench's 320x256 camera, f 333 px,
// turned straight down: footprint 0.77 m across x 0.62 m along track), with rover-like attitude wobble.
struct CameraWorld {
  sim::MarsYardTerrain terrain;
  sim::StereoBench bench;
  route::CameraIntrinsics k;
  double altitude_m = 0.8;
  explicit CameraWorld(std::uint64_t seed) : terrain([seed] {
      sim::MarsYardConfig c;
      c.seed = seed;
      return c;
    }()) {
    k.fx_px = k.fy_px = bench.focal_px();
    k.cu_px = bench.cu_px();
    k.cv_px = bench.cv_px();
  }
  double footprint_across_m() const { return bench.width() * altitude_m / bench.focal_px(); }
  double footprint_along_m() const { return bench.height() * altitude_m / bench.focal_px(); }
  // Camera pose in NED for a vehicle at (north, east) with compass heading and small roll / pitch:
  // camera x = starboard, y = aft (image top = forward), z = down.
  Pose3 ned_T_cam(double north, double east, double heading, double roll, double pitch) const {
    Mat3d body_R_cam;
    body_R_cam << 0, -1, 0, 1, 0, 0, 0, 0, 1;
    const Mat3d ned_R_body = rotation_from_rpy(roll, pitch, heading);
    return Pose3{ned_R_body * body_R_cam, Vec3d(north, east, -altitude_m)};
  }
  // The simulator's world is x, y, z up: north = x, east = -y, down = -z.
  Pose3 sim_T_cam(const Pose3& ned) const {
    const Mat3d F = Vec3d(1.0, -1.0, -1.0).asDiagonal();
    return Pose3{F * ned.R, F * ned.t};
  }
};

// A tile of a pass (node, nav_step_m: what the repeat component steps on) and its true centre.
struct CameraPassFrame : pipeline::RouteTile {
  double truth_north_m = 0.0;
};

// Renders one pass: frames every spacing_m from start_north towards end_north at east = lateral_m,
// heading north (or south when reverse); nav pose = truth in the pass's own dead-reckoned frame (origin
// shifted, 1 deg heading bias, 2 % odometry scale error, 0.3 deg compass noise).
Status camera_pass(const CameraWorld& w, pipeline::CameraTilePipeline& tiles, double start_north,
                   double end_north, double spacing_m, double lateral_m, bool taught, std::uint64_t seed, std::vector<CameraPassFrame>& out) {
  out.clear();
  const bool reverse = end_north < start_north;
  const double dir = reverse ? -1.0 : 1.0;
  const double heading0 = reverse ? kPi : 0.0;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double bias = taught ? 0.0 : deg_to_rad(1.0), scale = taught ? 1.0 : 1.02;
  const Vec2d origin = taught ? Vec2d(0.0, 0.0) : Vec2d(3.0, -2.0);
  Image<std::uint8_t> left = std::move(Image<std::uint8_t>::allocate(w.bench.width(), w.bench.height()).value());
  Image<std::uint8_t> right = std::move(Image<std::uint8_t>::allocate(w.bench.width(), w.bench.height()).value());
  double prev_n = start_north;
  for (int i = 0;; ++i) {
    const double n = start_north + dir * spacing_m * i;
    if (dir * (n - end_north) > 1e-9) break;
    const double yaw = heading0 + deg_to_rad(2.0) * std::sin(0.7 * n + static_cast<double>(seed % 7));
    const Pose3 cam = w.ned_T_cam(n, lateral_m, yaw, deg_to_rad(2.0) * n01(rng), deg_to_rad(2.0) * n01(rng));
    QNAV_RETURN_IF_ERROR(sim::render_stereo(w.terrain, w.bench, w.sim_T_cam(cam), seed * 1000003 + static_cast<std::uint64_t>(i), left.view(),
                                            right.view()));
    pipeline::CameraFrame frame;
    frame.image = left.view();
    frame.intrinsics = w.k;
    frame.ned_T_cam = cam;
    frame.heading_rad = yaw + bias + (taught ? 0.0 : deg_to_rad(0.3) * n01(rng));
    frame.nav_T_ground = Pose2{origin.x(), origin.y(), bias};  // the truth rotated by the heading bias and shifted
    CameraPassFrame f;
    Pose2 truth;
    QNAV_RETURN_IF_ERROR(tiles.push_frame(frame, f.node, &truth));
    const double true_centre_n = truth.x_m;
    f.node.meta.along_m = scale * spacing_m * i;
    f.nav_step_m = i == 0 ? 0.0 : scale * std::abs(n - prev_n);
    f.truth_north_m = true_centre_n;  // the tile centre (optical axis on the ground), true north
    prev_n = n;
    out.push_back(std::move(f));
  }
  return Status::ok();
}

}  // namespace

int cmd_camera() {
  const double length_m = g_opt.camera_length_m, spacing_m = 0.3;
  const long seed = g_opt.camera_seed;
  const bool json = g_opt.json;
  CameraWorld w(static_cast<std::uint64_t>(seed));
  const pipeline::CameraTileSettings settings = pipeline::camera_tile_settings();
  pipeline::CameraTilePipeline tiles;
  Status s = tiles.init(settings);
  std::vector<CameraPassFrame> taught;
  const auto t0 = Clock::now();
  if (s) s = camera_pass(w, tiles, 0.0, length_m, spacing_m, 0.0, true, static_cast<std::uint64_t>(seed) * 31 + 1, taught);
  if (!s || taught.size() < 2) {
    std::fprintf(stderr, "qnav route camera: teach: %s\n", s ? "fewer than 2 frames" : s.message());
    return 1;
  }
  std::vector<route::NodeMeta> meta;
  double kp = 0.0;
  for (std::size_t i = 0; i < taught.size(); ++i) {
    route::NodeMeta m = taught[i].node.meta;
    m.index = static_cast<std::uint32_t>(i);
    meta.push_back(m);
    kp += static_cast<double>(taught[i].node.keypoints.size());
  }
  const route::RouteParams params = pipeline::camera_route_params(settings, spacing_m, w.footprint_across_m());
  const double swath = w.footprint_across_m();
  if (!json)
    std::printf("camera route: %zu nodes over %.1f m (spacing %.2f m, footprint %.2f x %.2f m, %.0f keypoints/node), %.1f s to teach\n",
                taught.size(), length_m, spacing_m, swath, w.footprint_along_m(), kp / static_cast<double>(taught.size()), ms_since(t0) / 1000.0);
  const int pcts[] = {0, 10, 20, 30, 40};
  int scored = 0, within1 = 0, side_n = 0, side_ok = 0, off_route = 0;
  std::string rows;
  for (int rev = 0; rev < 2; ++rev) {
    for (const int pct : pcts) {
      const double lateral = pct / 100.0 * swath;
      std::vector<CameraPassFrame> rep;
      const double half = 0.5 * spacing_m;
      s = rev ? camera_pass(w, tiles, length_m - half, 0.0, spacing_m, lateral, false, static_cast<std::uint64_t>(seed) * 131 + pct * 2 + 1, rep)
              : camera_pass(w, tiles, half, length_m, spacing_m, lateral, false, static_cast<std::uint64_t>(seed) * 131 + pct * 2, rep);
      // The recorded-file configuration with its metric settings scaled from 0.3 m feature pixels to 4 mm.
      route::LocaliserConfig lc = pipeline::file_localiser_config(rev ? route::RouteDirection::kReverse : route::RouteDirection::kForward,
                                                        taught.size() + 8, taught.size(), spacing_m);
      lc.sensor = route::SensorKind::kCamera;
      lc.registration.robust.inlier_threshold_m = 0.02;
      lc.registration.fc.sigma_dist_m = 0.013;
      lc.guidance.side_deadband_m = 0.02;
      pipeline::RepeatSessionConfig sc;  // the repeat component without experiences
      sc.localiser = lc;
      sc.entry_prior = 0.0;  // the paper's uniform start: the figures docs/route.md quotes from this sweep
      auto session = std::make_unique<pipeline::RouteRepeatSession>(hal::host_file_store());
      VectorNodeSource<CameraPassFrame> src(&taught);
      if (s) s = session->init(sc);
      if (s) s = session->start(params, Span<const route::NodeMeta>(meta.data(), meta.size()), src, rev == 1);
      if (!s) {
        std::fprintf(stderr, "qnav route camera: %s\n", s.message());
        return 1;
      }
      int p_scored = 0, p_within = 0, p_side_n = 0, p_side_ok = 0, p_off = 0, p_track = 0;
      for (std::size_t k = 0; k < rep.size(); ++k) {
        route::LocaliserStep st;
        s = session->step(rep[k], false, st).step;
        if (!s) {
          std::fprintf(stderr, "qnav route camera: %s\n", s.message());
          return 1;
        }
        const int truth = static_cast<int>(std::lround(std::clamp(rep[k].truth_north_m / spacing_m, 0.0, static_cast<double>(taught.size() - 1))));
        const route::RouteSide want = expected_side(lateral, rev == 1, lc.guidance.side_deadband_m);
        p_track += st.guidance.status == route::GuidanceStatus::kTracking;
        if (k < static_cast<std::size_t>(kWarmupTiles)) continue;
        ++p_scored;
        p_within += std::abs(static_cast<int>(st.estimate) - truth) <= 1;
        if (want != route::RouteSide::kOnRoute) {
          ++p_off;
          const bool decided = st.guidance.side != route::RouteSide::kUnknown;
          p_side_n += decided;
          p_side_ok += decided && st.guidance.side == want;
        }
      }
      scored += p_scored;
      within1 += p_within;
      side_n += p_side_n;
      side_ok += p_side_ok;
      off_route += p_off;
      char line[256];
      std::snprintf(line, sizeof line, "  %-7s %3d%% (%.2f m)  %2zu frames  node +/-1 %5.1f%%  side correct %2d/%2d of %2d off-route  tracking %2d\n",
                    rev ? "reverse" : "forward", pct, lateral, rep.size(), p_scored ? 100.0 * p_within / p_scored : 0.0, p_side_ok, p_side_n, p_off,
                    p_track);
      rows += line;
    }
  }
  const double w1 = scored ? 100.0 * within1 / scored : 0.0, sc = side_n ? 100.0 * side_ok / side_n : 0.0,
               sall = off_route ? 100.0 * side_ok / off_route : 0.0;
  if (json) {
    std::printf("{\"sensor\":\"camera\",\"nodes\":%zu,\"spacing_m\":%.2f,\"footprint_m\":[%.3f,%.3f],\"keypoints_per_node\":%.1f,"
                "\"scored_tiles\":%d,\"node_within_1_pct\":%.2f,\"side_correct_pct\":%.2f,\"side_decided\":%d,"
                "\"side_correct_pct_of_offset_tiles\":%.2f,\"offset_tiles\":%d}\n",
                taught.size(), spacing_m, swath, w.footprint_along_m(), kp / static_cast<double>(taught.size()), scored, w1, sc, side_n, sall,
                off_route);
  } else {
    std::fputs(rows.c_str(), stdout);
    std::printf("all passes: node within +/-1 on %d of %d scored tiles (%.1f%%); side correct on %d of %d decided (%.1f%%), %.1f%% of %d off-route tiles\n",
                within1, scored, w1, side_ok, side_n, sc, sall, off_route);
  }
  return 0;
}

}  // namespace route_cmd
