// qnav route: eval, the route-following paper's evaluation on the simulator (split from route.cpp; what the files share: route_cmd.hpp).
#include "firmware/qnav/commands/route/route_cmd.hpp"

namespace route_cmd {

// ---------------------------------------------------------------------------------------------------
// qnav route eval
namespace {

struct TileRecord {
  int seabed = 1;
  int pct = 0;
  bool reverse = false;
  int tile = 0;
  int truth = -1;
  route::LocaliserStep st;
  route::RouteSide want = route::RouteSide::kOnRoute;
  double true_cross_track_m = 0.0;  // the pass's offset, signed like GuidanceOutput::cross_track_m (exact on straight legs)
};

struct PassStats {
  int seabed = 1;
  int pct = 0;
  bool reverse = false;
  double lateral_m = 0.0;
  int tiles = 0, scored = 0, within1 = 0, side_n = 0, side_ok = 0, tracking = 0;
  int off_route = 0;  // scored tiles whose true side is port or starboard
  int dead_reckoned = 0;  // scored tiles steered on dead reckoning from the last fix
  double mean_entropy = 0.0;
  int reg_true_ok = 0;               // tiles that register (S > chance) on their true node
  double reg_true_mean_inliers = 0.0;
  int reg_false_ok = 0;              // tiles that register on a node 3+ away (chance consensus)
  int reg_true_right = 0;            // ... of reg_true_ok, with the transform right (simulator truth)
  double repeated_keypoints = 0.0;   // mean per tile: sensed keypoints with a node keypoint on the same spot
};


// The filter step of tile k of a pass: a bare RouteRepeater (the pass's first tile: no travel yet), or
// the repeat component qnavd and `route repeat` run (pipeline::RouteRepeatSession, which counts the
// pass's tiles itself; dvl_lost: the paper's eq. 5 motion model).
Status step_tile(pipeline::RouteRepeater& loc, const pipeline::RouteTile& tile, std::size_t k, route::LocaliserStep& st) {
  return loc.step(tile.node, k == 0 ? 0.0 : tile.nav_step_m, st);
}
struct SessionStepper {
  pipeline::RouteRepeatSession& session;
  bool dvl_lost = false;
};
Status step_tile(SessionStepper& s, const pipeline::RouteTile& tile, std::size_t, route::LocaliserStep& st) {
  return s.session.step(tile, s.dvl_lost, st).step;
}

// One localiser update on tile k of a pass, scored against the simulator's truth into ps (and records).
template <class Localiser>
Status localise_tile(Localiser& loc, const pipeline::RouteTile& tile, std::size_t k, const std::vector<double>& node_along, int pct,
                     bool reverse, double lateral, double deadband, std::vector<TileRecord>* records, PassStats& ps, std::vector<double>* step_ms,
                     std::vector<double>* step_cpu_ms, route::LocaliserStep* step_out = nullptr) {
  ps.pct = pct;
  ps.reverse = reverse;
  ps.lateral_m = lateral;
  TileRecord r;
  r.pct = pct;
  r.reverse = reverse;
  r.tile = static_cast<int>(k);
  const auto t0 = Clock::now();
  const double c0 = cpu_ms();
  QNAV_RETURN_IF_ERROR(step_tile(loc, tile, k, r.st));
  if (step_cpu_ms) step_cpu_ms->push_back(cpu_ms() - c0);
  if (step_ms) step_ms->push_back(ms_since(t0));
  r.truth = true_node(node_along, tile.truth_along_m);
  r.want = expected_side(lateral, reverse, deadband);
  r.true_cross_track_m = reverse ? -lateral : lateral;
  ++ps.tiles;
  ps.mean_entropy += r.st.entropy;
  if (static_cast<int>(k) >= kWarmupTiles) {
    ++ps.scored;
    ps.within1 += std::abs(static_cast<int>(r.st.estimate) - r.truth) <= 1;
    ps.off_route += r.want != route::RouteSide::kOnRoute;
    ps.tracking += r.st.guidance.status == route::GuidanceStatus::kTracking;
    ps.dead_reckoned += r.st.guidance.status == route::GuidanceStatus::kDeadReckoned;
    if (r.want != route::RouteSide::kOnRoute && r.st.guidance.side != route::RouteSide::kUnknown) {  // a side was given
      ++ps.side_n;
      ps.side_ok += r.st.guidance.side == r.want;
    }
  }
  if (step_out) *step_out = r.st;
  if (records) records->push_back(r);
  return Status::ok();
}

template <class Localiser>
Status run_localiser(Localiser& loc, const std::vector<pipeline::RouteTile>& tiles, const std::vector<double>& node_along,
                     int pct, bool reverse, double lateral, double deadband, std::vector<TileRecord>* records, PassStats& ps,
                     std::vector<double>* step_ms, std::vector<double>* step_cpu_ms = nullptr) {
  for (std::size_t k = 0; k < tiles.size(); ++k)
    QNAV_RETURN_IF_ERROR(localise_tile(loc, tiles[k], k, node_along, pct, reverse, lateral, deadband, records, ps, step_ms, step_cpu_ms));
  if (ps.tiles) ps.mean_entropy /= ps.tiles;
  return Status::ok();
}

// Flies a pass and localises each tile as it is built through the repeat component (a started
// session), framing the next tile on the route (RouteRepeatSession::next_stride_m), as qnavd and
// `route repeat` do.
Status fly_localised(pipeline::RouteTilePipeline& pipe, const pipeline::SimSurvey& w, const sidescan::TrajectoryConfig& traj,
                     pipeline::RouteRepeatSession& session, const std::vector<double>& node_along, int pct, bool reverse,
                     double lateral, double deadband, std::vector<TileRecord>* records, PassStats& ps, std::vector<pipeline::RouteTile>& tiles) {
  tiles.clear();
  Status step_status;
  SessionStepper loc{session, false};
  QNAV_RETURN_IF_ERROR(pipe.run_sim_pass(w.seabed, w.sonar_for(traj.seed), traj, [&](const pipeline::RouteTile& t) {
    tiles.push_back(t);
    route::LocaliserStep st;
    step_status = localise_tile(loc, t, tiles.size() - 1, node_along, pct, reverse, lateral, deadband, records, ps, nullptr, nullptr, &st);
    if (!step_status) return false;
    if (!g_opt.no_align) pipe.set_next_stride_m(session.next_stride_m(st, pipe.config().tiles.tile_stride_m));
    return true;
  }));
  if (ps.tiles) ps.mean_entropy /= ps.tiles;
  return step_status;
}

// Registration alone, without the filter: each tile against its true node and against a node three
// away (a chance consensus there is what the measurement floor must absorb). With the simulator's
// true poses also: keypoints that repeat (a node keypoint within 1.5 m of the same seabed spot) and
// whether the registered transform is right (tile origin within 5 m of where the truth puts it).
void registration_at_truth(const route::RegistrationConfig& rc, const std::vector<pipeline::RouteTile>& train, const std::vector<pipeline::RouteTile>& tiles,
                           const std::vector<double>& node_along, PassStats& ps) {
  ArenaStorage arena(route::Registrar::arena_bytes(rc));
  auto reg = std::make_unique<route::Registrar>();
  if (!reg->init(rc, arena)) return;
  const int n = static_cast<int>(train.size());
  const double chance = static_cast<double>(rc.robust.min_inliers);
  double sum = 0.0, rep = 0.0;
  for (const pipeline::RouteTile& t : tiles) {
    const int tn = true_node(node_along, t.truth_along_m);
    if (tn < 0 || tn >= n) continue;
    const pipeline::RouteTile& node = train[static_cast<std::size_t>(tn)];
    route::RegistrationResult r;
    if (reg->register_tile(t.node, node.node, r)) {
      sum += r.inliers;
      ps.reg_true_ok += r.ok && r.inliers > chance;
      if (r.ok && r.inliers > chance && t.has_truth_pose && node.has_truth_pose) {
        const Vec2d truth = node.truth_pose.inverse().apply(t.truth_pose.translation());
        ps.reg_true_right += (r.sensed_to_node.translation() - truth).norm() < 5.0;
      }
    }
    if (t.has_truth_pose && node.has_truth_pose)
      for (const route::RouteKeypoint& a : t.node.keypoints) {
        const Vec2d wa = t.truth_pose.apply(Vec2d(a.x_m, a.y_m));
        for (const route::RouteKeypoint& b : node.node.keypoints)
          if ((node.truth_pose.apply(Vec2d(b.x_m, b.y_m)) - wa).norm() < 1.5) {
            rep += 1.0;
            break;
          }
      }
    const int far = tn + 3 < n ? tn + 3 : tn - 3;
    if (far >= 0 && reg->register_tile(t.node, train[static_cast<std::size_t>(far)].node, r)) ps.reg_false_ok += r.ok && r.inliers > chance;
  }
  ps.reg_true_mean_inliers = tiles.empty() ? 0.0 : sum / static_cast<double>(tiles.size());
  ps.repeated_keypoints = tiles.empty() ? 0.0 : rep / static_cast<double>(tiles.size());
}

struct SweepInputs {
  pipeline::RouteTilePipeline* pipe;
  const pipeline::SimSurvey* world;
  const std::vector<pipeline::RouteTile>* train;
  route::NodeSource* source;
  const route::RouteParams* params;
  Span<const route::NodeMeta> meta;
  const std::vector<double>* node_along;
  const std::vector<int>* pcts;
  int seabed;
  FILE* log;
  double entry_prior = 0.0;  // the paper's uniform start unless a caller says otherwise
};

// Repeat passes at every offset, forwards and in reverse, over one taught route. kidnap_src (if
// given) receives the 20% forward pass's tiles; eq5_within the paper's motion model on that pass.
Status offset_sweep(const SweepInputs& in, int& pass_seed, std::vector<TileRecord>& records, std::vector<PassStats>& stats,
                    std::vector<pipeline::RouteTile>* kidnap_src, double* eq5_within) {
  std::vector<pipeline::RouteTile> tiles;
  const std::size_t nodes = in.meta.size();
  for (int pct : *in.pcts) {
    for (bool rev : {false, true}) {
      const double lateral = pct / 100.0 * in.world->swath_m;
      const auto t0 = Clock::now();
      route::LocaliserConfig lc = pipeline::default_localiser_config(rev ? route::RouteDirection::kReverse : route::RouteDirection::kForward, nodes);
      pipeline::RepeatSessionConfig sc;  // the repeat component without experiences
      sc.localiser = lc;
      sc.entry_prior = in.entry_prior;  // 0 (the paper's uniform start) for route eval's figures
      auto session = std::make_unique<pipeline::RouteRepeatSession>(hal::host_file_store());
      QNAV_RETURN_IF_ERROR(session->init(sc));
      QNAV_RETURN_IF_ERROR(session->start(*in.params, in.meta, *in.source, rev));
      PassStats ps;
      ps.seabed = in.seabed;
      std::vector<TileRecord> rec;
      QNAV_RETURN_IF_ERROR(fly_localised(*in.pipe, *in.world, in.world->pass(lateral, rev, static_cast<std::uint64_t>(++pass_seed)), *session,
                                         *in.node_along, pct, rev, lateral, lc.guidance.side_deadband_m, &rec, ps, tiles));
      for (TileRecord& r : rec) {
        r.seabed = in.seabed;
        records.push_back(r);
      }
      registration_at_truth(lc.registration, *in.train, tiles, *in.node_along, ps);
      stats.push_back(ps);
      std::fprintf(in.log, "  seabed %d offset %2d%% (%5.1f m) %-7s: %3d tiles, node +/-1 %5.1f%%, side correct %d/%d, tracking %d/%d; registration alone: on the true node %d/%d (transform right %d, mean S %.1f, repeated keypoints %.1f), on a node 3 away %d (%.1f s)\n",
                   in.seabed, pct, lateral, rev ? "reverse" : "forward", ps.tiles, ps.scored ? 100.0 * ps.within1 / ps.scored : 0.0, ps.side_ok, ps.side_n,
                   ps.tracking, ps.scored, ps.reg_true_ok, ps.tiles, ps.reg_true_right, ps.reg_true_mean_inliers, ps.repeated_keypoints, ps.reg_false_ok,
                   ms_since(t0) / 1000.0);
      if (pct == 20 && !rev && kidnap_src != nullptr) *kidnap_src = tiles;
      if (pct == 20 && !rev && eq5_within != nullptr) {
        // The paper's motion model (eq. 5) on the same tiles, for comparison: the repeat component
        // as while the DVL is lost.
        auto s5 = std::make_unique<pipeline::RouteRepeatSession>(hal::host_file_store());
        SessionStepper l5{*s5, true};
        PassStats p5;
        if (s5->init(sc) && s5->start(*in.params, in.meta, *in.source, rev) &&
            run_localiser(l5, tiles, *in.node_along, pct, rev, lateral, lc.guidance.side_deadband_m, nullptr, p5, nullptr))
          *eq5_within = p5.scored ? 100.0 * p5.within1 / p5.scored : 0.0;
      }
    }
  }
  if (kidnap_src != nullptr && kidnap_src->empty()) *kidnap_src = tiles;
  return Status::ok();
}

bool ensure_dir(const std::string& d) {
  struct stat st {};
  if (::stat(d.c_str(), &st) == 0) return S_ISDIR(st.st_mode);
  return ::mkdir(d.c_str(), 0755) == 0;
}

// What the steps of `route eval` share: the survey, the tile pipeline, the route taught on it (written
// to the route file and read back: its reader is the repeats' node source) and where to report.
struct EvalRun {
  double length_m = 0.0;
  std::string out_dir;
  FILE* log = stdout;
  pipeline::SimSurvey w;
  pipeline::RouteTilePipeline pipe;
  std::vector<pipeline::RouteTile> train;
  tools::RouteFileReader reader;
  std::vector<route::NodeMeta> meta;
  std::vector<double> node_along;  // each node's true along-track distance
  double spacing = 0.0;
  Span<const route::NodeMeta> meta_span() const { return Span<const route::NodeMeta>(meta.data(), meta.size()); }
};

// 1. Teach: a forward pass on the route, written durably node by node, then opened again. Returns
//    the command's exit code (0: taught).
int teach_eval(EvalRun& e) {
  auto t0 = Clock::now();
  Status s = fly(e.pipe, e.w, e.w.pass(0.0, false, 11), e.train);
  if (!s || e.train.size() < 2) {
    std::fprintf(stderr, "qnav route eval: training pass failed: %s\n", s ? "fewer than 2 tiles" : s.message());
    return 1;
  }
  const std::vector<pipeline::RouteTile>& train = e.train;
  const double fly_ms = ms_since(t0);
  e.spacing = (train.back().node.meta.along_m - train.front().node.meta.along_m) / static_cast<double>(train.size() - 1);
  const std::string route_path = e.out_dir + "/route_eval.qroute";
  tools::RouteFileWriter writer;
  if (!begin_route(writer, "eval", route_path.c_str(), pipeline::side_scan_route_params(e.pipe.config(), e.spacing, e.w.swath_m), true)) return 1;
  t0 = Clock::now();
  for (const pipeline::RouteTile& t : train)
    if (s) s = writer.append(t.node);
  const double append_ms = ms_since(t0) / static_cast<double>(train.size());
  if (!finish_route(writer, "eval", route_path.c_str(), s)) return 1;
  s = e.reader.open(route_path.c_str());
  std::uint32_t bad = 0;
  if (s) s = e.reader.read_all_meta(e.meta, &bad);
  if (!s) {
    std::fprintf(stderr, "qnav route eval: route file: %s\n", s.message());
    return 1;
  }
  double kp_mean = 0.0;
  for (const pipeline::RouteTile& t : train) {
    e.node_along.push_back(t.truth_along_m);
    kp_mean += static_cast<double>(t.node.keypoints.size());
  }
  kp_mean /= static_cast<double>(train.size());
  std::fprintf(e.log, "taught: %zu nodes over %.0f m (spacing %.1f m, swath %.1f m, %.1f keypoints/node), pass %.1f s, append+fdatasync %.2f ms/node\n",
               train.size(), e.length_m, e.spacing, e.w.swath_m, kp_mean, fly_ms / 1000.0, append_ms);
  return 0;
}

// 2. (further seabeds) Seabed sb taught afresh, nodes in memory, and swept like the first.
Status sweep_seabed(EvalRun& e, long sb, const std::vector<int>& pcts, int& pass_seed, std::vector<TileRecord>& records,
                    std::vector<PassStats>& stats, bool& taught) {
  pipeline::SimSurvey w2;
  std::vector<pipeline::RouteTile> train2;
  taught = false;
  Status s = w2.init(e.length_m, static_cast<std::uint64_t>(sb));
  if (s) s = fly(e.pipe, w2, w2.pass(0.0, false, 11 + 1000 * static_cast<std::uint64_t>(sb)), train2);
  if (!s || train2.size() < 2) return s;
  taught = true;
  const double sp2 = (train2.back().node.meta.along_m - train2.front().node.meta.along_m) / static_cast<double>(train2.size() - 1);
  const route::RouteParams p2 = pipeline::side_scan_route_params(e.pipe.config(), sp2, w2.swath_m);
  std::vector<route::NodeMeta> meta2;
  std::vector<double> along2;
  for (std::size_t i = 0; i < train2.size(); ++i) {
    meta2.push_back(train2[i].node.meta);
    meta2.back().index = static_cast<std::uint32_t>(i);
    along2.push_back(train2[i].truth_along_m);
  }
  TileSource src2(&train2);
  std::fprintf(e.log, "seabed %ld: taught %zu nodes (spacing %.1f m)\n", sb, train2.size(), sp2);
  SweepInputs in2{&e.pipe, &w2, &train2, &src2, &p2, Span<const route::NodeMeta>(meta2.data(), meta2.size()), &along2, &pcts, static_cast<int>(sb), e.log};
  return offset_sweep(in2, pass_seed, records, stats, nullptr, nullptr);
}

// The sweep's totals over every pass (side counts only on passes off the route, > 5 %).
struct SweepTotals {
  int scored = 0, within = 0, side_n = 0, side_ok = 0, tracking = 0, off_route = 0, dead_reckoned = 0;
  std::vector<double> seed_within;  // node +/-1 per seabed
};
SweepTotals sum_sweep(const std::vector<PassStats>& stats, long seabeds) {
  SweepTotals t;
  for (long sb = 1; sb <= seabeds; ++sb) {
    int sc = 0, wi = 0;
    for (const PassStats& p : stats)
      if (p.seabed == sb) {
        sc += p.scored;
        wi += p.within1;
      }
    t.seed_within.push_back(sc ? 100.0 * wi / sc : 0.0);
  }
  for (const PassStats& p : stats) {
    t.scored += p.scored;
    t.within += p.within1;
    t.tracking += p.tracking;
    t.dead_reckoned += p.dead_reckoned;
    if (p.pct > 5) {
      t.side_n += p.side_n;
      t.side_ok += p.side_ok;
      t.off_route += p.off_route;
    }
  }
  return t;
}

// 3. Kidnapped vehicle: after 8 tiles the vehicle is moved a third of the route ahead; odometry
//    does not know. Tiles until the estimate is within +/-1 and stays there for 3 tiles (-1: never).
int kidnapped(EvalRun& e, const std::vector<pipeline::RouteTile>& kidnap_src) {
  int relocalised = -1;
  const std::size_t jump_from = 8, jump_to = 8 + kidnap_src.size() / 3;
  std::vector<pipeline::RouteTile> seq(kidnap_src.begin(), kidnap_src.begin() + static_cast<long>(std::min(jump_from, kidnap_src.size())));
  for (std::size_t i = jump_to; i < kidnap_src.size(); ++i) seq.push_back(kidnap_src[i]);
  route::LocaliserConfig lc = pipeline::default_localiser_config(route::RouteDirection::kForward, e.meta.size());
  auto loc = std::make_unique<pipeline::RouteRepeater>();
  PassStats ps;
  std::vector<TileRecord> rec;
  if (loc->init(lc) && loc->start(e.reader.params(), e.meta_span(), e.reader) &&
      run_localiser(*loc, seq, e.node_along, 20, false, 0.2 * e.w.swath_m, lc.guidance.side_deadband_m, &rec, ps, nullptr)) {
    if (std::getenv("QNAV_ROUTE_DIAG"))
      for (const TileRecord& r : rec)
        std::fprintf(stderr, "kidnap tile %d truth %d est %u p %.2f inliers %u conf %d\n", r.tile, r.truth, r.st.estimate,
                     static_cast<double>(r.st.probability), r.st.best_inliers, r.st.confident ? 1 : 0);
    for (std::size_t k = jump_from; k + 2 < rec.size(); ++k) {
      bool ok = true;
      for (std::size_t j = k; j < k + 3; ++j) ok = ok && std::abs(static_cast<int>(rec[j].st.estimate) - rec[j].truth) <= 1;
      if (ok) {
        relocalised = static_cast<int>(k - jump_from) + 1;
        break;
      }
    }
  }
  std::fprintf(e.log, "kidnapped after tile %zu (moved %zu tiles ahead): re-localised after %d tiles\n", jump_from, jump_to - jump_from, relocalised);
  return relocalised;
}

// 4. Speed on a 10,000-node route read from a file through the node window (-1: not measured).
struct UpdateSpeed {
  double mean = -1, p95 = -1, max = -1, cpu_mean = -1, cpu_max = -1;
};
UpdateSpeed speed_10000(EvalRun& e, const std::vector<pipeline::RouteTile>& tiles) {
  UpdateSpeed u;
  const std::vector<pipeline::RouteTile>& train = e.train;
  const std::string big = e.out_dir + "/route_10000.qroute";
  tools::RouteFileWriter bw;
  tools::RouteWriterOptions o;
  o.sync_each_node = false;
  Status bs = begin_route(bw, "eval", big.c_str(), pipeline::side_scan_route_params(e.pipe.config(), e.spacing, e.w.swath_m), true, o)
                  ? Status::ok()
                  : Status(StatusCode::kIoError, "cannot create the 10,000-node route");
  const double block_m = e.node_along.back() + e.spacing;
  for (std::uint32_t i = 0; i < 10000 && bs; ++i) {
    route::RouteNode n = train[i % train.size()].node;
    const double shift = block_m * static_cast<double>(i / train.size());
    n.meta.pose.x_m += shift;
    n.meta.along_m += shift;
    bs = bw.append(n);
  }
  if (!finish_route(bw, "eval", big.c_str(), bs) && bs) bs = Status(StatusCode::kIoError, "10,000-node route not committed");
  tools::RouteFileReader br;
  std::vector<route::NodeMeta> bmeta;
  if (bs) bs = br.open(big.c_str());
  if (bs) bs = br.read_all_meta(bmeta, nullptr);
  route::LocaliserConfig lc = pipeline::default_localiser_config(route::RouteDirection::kForward, 10000);
  auto loc = std::make_unique<pipeline::RouteRepeater>();
  const double window_mb = static_cast<double>(route::RouteLocaliser::arena_bytes(lc)) / 1e6;
  if (bs) bs = loc->init(lc);
  if (bs) bs = loc->start(br.params(), Span<const route::NodeMeta>(bmeta.data(), bmeta.size()), br);
  std::vector<double> ms, cms;
  PassStats ps;
  std::vector<double> along_big;  // truth unknown on the replicated route: scoring not used
  along_big.push_back(0.0);
  if (bs) bs = run_localiser(*loc, tiles, along_big, 20, false, 0.0, 1.0, nullptr, ps, &ms, &cms);
  if (bs && !ms.empty()) {
    std::sort(ms.begin(), ms.end());
    double sum = 0;
    for (double v : ms) sum += v;
    u.mean = sum / static_cast<double>(ms.size());
    u.p95 = ms[static_cast<std::size_t>(0.95 * static_cast<double>(ms.size() - 1))];
    u.max = ms.back();
    double cs = 0;
    for (double v : cms) cs += v;
    u.cpu_mean = cs / static_cast<double>(cms.size());
    u.cpu_max = *std::max_element(cms.begin(), cms.end());
  }
  std::remove(big.c_str());
  std::fprintf(e.log, "10,000-node route (file, %zu-node window): update wall mean %.2f ms, p95 %.2f ms, max %.2f ms; thread CPU mean %.2f ms, max %.2f ms over %zu tiles; localiser memory %.1f MB\n",
               lc.window_slots, u.mean, u.p95, u.max, u.cpu_mean, u.cpu_max, ms.size(), window_mb);
  return u;
}

// 5. Prediction alone on 100,000 nodes: wall and thread CPU ms per predict (-1: not measured).
void predict_100000(double spacing, FILE* log, double& pred_ms, double& pred_cpu_ms) {
  pred_ms = -1;
  pred_cpu_ms = -1;
  route::RouteFilterConfig fc;
  fc.max_nodes = 100000;
  ArenaStorage arena(route::RouteFilter::arena_bytes(fc));
  route::RouteFilter f;
  if (f.init(fc, arena) && f.reset(100000, spacing)) {
    const int reps = 200;
    const auto t0 = Clock::now();
    const double c0 = cpu_ms();
    for (int i = 0; i < reps; ++i) f.predict(spacing).ignore();
    pred_cpu_ms = (cpu_ms() - c0) / reps;
    pred_ms = ms_since(t0) / reps;
  }
  std::fprintf(log, "prediction alone, 100,000 nodes: wall %.3f ms, thread CPU %.3f ms\n", pred_ms, pred_cpu_ms);
}

// 6. One sensed tile of the paper-shaped run: a row of Table I (t1), Fig. 5 (f5: measurement
//    probability per node), Fig. 7 (f7: belief per node) and Fig. 9 (f9: positions), scored.
struct PaperFiles {
  FILE *t1, *f5, *f7, *f9;
};
Status paper_tile(EvalRun& e, pipeline::RouteRepeater& loc, const pipeline::RouteTile& sensed, std::size_t k, double lateral, double deadband,
                  const std::vector<double>& sub_along, const sidescan::Trajectory& tr, const PaperFiles& out, std::vector<float>& mp, int& localised,
                  int& side) {
  route::LocaliserStep st;
  QNAV_RETURN_IF_ERROR(loc.step(sensed.node, k == 0 ? 0.0 : sensed.nav_step_m, st));
  const int truth = true_node(sub_along, sensed.truth_along_m);
  const route::RouteSide want = expected_side(lateral, false, deadband);
  localised += std::abs(static_cast<int>(st.estimate) - truth) <= 0 ? 1 : 0;
  side += st.guidance.side == want;
  std::fprintf(out.t1, "%zu,%u,%d,%.3f,%s,%s,%u\n", k + 1, st.estimate + 1, truth + 1, st.entropy, route::to_string(st.guidance.side),
               route::to_string(want), st.best_inliers);
  std::fprintf(e.log, "  %6zu  %8u  %5d  %7.2f  %-9s  %s\n", k + 1, st.estimate + 1, truth + 1, st.entropy, route::to_string(st.guidance.side),
               route::to_string(want));
  loc.localiser().filter().measurement_probability(Span<float>(mp.data(), mp.size())).ignore();
  for (std::size_t i = 0; i < sub_along.size(); ++i) {
    std::fprintf(out.f5, "%s%.5f", i ? "," : "", static_cast<double>(mp[i]));
    std::fprintf(out.f7, "%s%.5f", i ? "," : "", static_cast<double>(loc.localiser().filter().belief()[i]));
  }
  std::fprintf(out.f5, "\n");
  std::fprintf(out.f7, "\n");
  Vec2d tp, np;
  double th, nh;
  tr.route_at(sensed.truth_along_m, tp, th);
  tr.route_at(sub_along[st.estimate], np, nh);
  tp += lateral * sonar::starboard_unit(th);
  std::fprintf(out.f9, "%zu,%.2f,%.2f,%.2f,%.2f,%.2f,%s,%s,%.3f,%s\n", k + 1, tp.x(), tp.y(), np.x(), np.y(), st.guidance.cross_track_m,
               route::to_string(st.guidance.side), route::to_string(want), st.entropy, route::to_string(st.guidance.status));
  return Status::ok();
}

// 6. The paper's experiment shape: 15 training nodes, 8 sensed tiles (offset 25% of swath), every
//    node registered each step (the paper's eq. 8 over the whole database). Table I, Fig. 5, 7, 9, 10.
void paper_run(EvalRun& e, int& paper_localised, int& paper_side) {
  paper_localised = 0;
  paper_side = 0;
  const std::vector<pipeline::RouteTile>& train = e.train;
  const std::size_t a = train.size() / 3;
  const std::size_t n15 = std::min<std::size_t>(15, train.size() - a);
  std::vector<pipeline::RouteTile> sub(train.begin() + static_cast<long>(a), train.begin() + static_cast<long>(a + n15));
  std::vector<route::NodeMeta> sub_meta;
  std::vector<double> sub_along;
  for (std::size_t i = 0; i < sub.size(); ++i) {
    route::NodeMeta m = sub[i].node.meta;
    m.index = static_cast<std::uint32_t>(i);
    sub_meta.push_back(m);
    sub_along.push_back(sub[i].truth_along_m);
  }
  const double lateral = 0.25 * e.w.swath_m;
  std::vector<pipeline::RouteTile> pass;
  Status s = fly(e.pipe, e.w, e.w.pass(lateral, false, 999), pass);
  std::vector<pipeline::RouteTile> sensed;
  for (const pipeline::RouteTile& t : pass)
    if (t.truth_along_m >= sub_along[std::min<std::size_t>(5, sub_along.size() - 1)] - 0.5 * e.spacing && sensed.size() < 8) sensed.push_back(t);
  TileSource src(&sub);
  route::LocaliserConfig lc = pipeline::default_localiser_config(route::RouteDirection::kForward, 64);
  lc.filter.belief_registrations = static_cast<std::uint32_t>(sub.size());
  lc.filter.wide_search_registrations = 0;
  auto loc = std::make_unique<pipeline::RouteRepeater>();
  const PaperFiles out{std::fopen((e.out_dir + "/route_table1.csv").c_str(), "w"), std::fopen((e.out_dir + "/route_fig5.csv").c_str(), "w"),
                       std::fopen((e.out_dir + "/route_fig7.csv").c_str(), "w"), std::fopen((e.out_dir + "/route_fig9.csv").c_str(), "w")};
  if (s && out.t1 && out.f5 && out.f7 && out.f9 && loc->init(lc) &&
      loc->start(e.reader.params(), Span<const route::NodeMeta>(sub_meta.data(), sub_meta.size()), src)) {
    std::fprintf(out.t1, "sensed,estimate,truth,entropy,side,true_side,inliers\n");
    std::fprintf(out.f9, "sensed,true_north,true_east,node_north,node_east,cross_track_m,side,true_side,entropy,status\n");
    std::fprintf(e.log, "paper-shaped run (15 nodes, 8 sensed tiles, offset 25%% = %.1f m):\n  sensed  estimate  truth  entropy  side       true side\n", lateral);
    std::vector<float> mp(sub.size());
    sidescan::Trajectory tr;
    s = tr.init(e.w.route);
    for (std::size_t k = 0; k < sensed.size() && s; ++k)
      s = paper_tile(e, *loc, sensed[k], k, lateral, lc.guidance.side_deadband_m, sub_along, tr, out, mp, paper_localised, paper_side);
    std::fprintf(e.log, "  localised (exact node) %d/8, side correct %d/8 (paper: 7/8 and 6/8)\n", paper_localised, paper_side);
  }
  for (FILE* f : {out.t1, out.f5, out.f7, out.f9})
    if (f) std::fclose(f);
}

// CSV outputs for the plots: one row per offset and direction, summed over the seabeds.
void write_offsets_csv(const std::string& out_dir, const std::vector<int>& pcts, const std::vector<PassStats>& stats) {
  FILE* f = std::fopen((out_dir + "/route_eval_offsets.csv").c_str(), "w");
  if (f == nullptr) return;
  std::fprintf(f, "offset_pct,lateral_m,direction,tiles,scored,within1_pct,side_correct,side_n,tracking_pct,mean_entropy,seabeds,registered_on_true_node_pct\n");
  for (int pct : pcts)
    for (bool rev : {false, true}) {
      PassStats a;
      int n = 0, reg = 0;
      for (const PassStats& p : stats)
        if (p.pct == pct && p.reverse == rev) {
          a.lateral_m = p.lateral_m;
          a.tiles += p.tiles;
          a.scored += p.scored;
          a.within1 += p.within1;
          a.side_ok += p.side_ok;
          a.side_n += p.side_n;
          a.tracking += p.tracking;
          a.mean_entropy += p.mean_entropy;
          reg += p.reg_true_ok;
          ++n;
        }
      if (n == 0) continue;
      std::fprintf(f, "%d,%.2f,%s,%d,%d,%.2f,%d,%d,%.2f,%.4f,%d,%.2f\n", pct, a.lateral_m, rev ? "reverse" : "forward", a.tiles, a.scored,
                   a.scored ? 100.0 * a.within1 / a.scored : 0.0, a.side_ok, a.side_n, a.scored ? 100.0 * a.tracking / a.scored : 0.0,
                   a.mean_entropy / n, n, a.tiles ? 100.0 * reg / a.tiles : 0.0);
    }
  std::fclose(f);
}

void write_tiles_csv(const std::string& out_dir, const std::vector<TileRecord>& records) {
  FILE* f = std::fopen((out_dir + "/route_eval_tiles.csv").c_str(), "w");
  if (f == nullptr) return;
  std::fprintf(f, "offset_pct,direction,tile,true_node,estimate,probability,entropy,confident,inliers,status,side,true_side,cross_track_m,seabed,"
                  "cross_track_sigma_m,offsets,true_cross_track_m\n");
  for (const TileRecord& r : records)
    std::fprintf(f, "%d,%s,%d,%d,%u,%.4f,%.4f,%d,%u,%s,%s,%s,%.2f,%d,%.2f,%s,%.2f\n", r.pct, r.reverse ? "reverse" : "forward", r.tile, r.truth,
                 r.st.estimate, static_cast<double>(r.st.probability), r.st.entropy, r.st.confident ? 1 : 0, r.st.best_inliers,
                 route::to_string(r.st.guidance.status), route::to_string(r.st.guidance.side), route::to_string(r.want), r.st.guidance.cross_track_m,
                 r.seabed, r.st.guidance.cross_track_sigma_m, route::to_string(r.st.guidance.offsets), r.true_cross_track_m);
  std::fclose(f);
}

// What `route eval` prints last (one JSON object with --json, else one line).
struct EvalSummary {
  SweepTotals t;
  std::vector<int> pcts;
  long seabeds = 0;
  int relocalised = -1, paper_localised = 0, paper_side = 0;
  double eq5_within = -1.0, pred_ms = -1, pred_cpu_ms = -1;
  UpdateSpeed upd;
  int dr_n = 0, dr_in = 0;  // off-route scored tiles with offsets from dead reckoning; of them within 2 sigma
};
void print_eval_summary(const EvalRun& e, const EvalSummary& m, bool json, Clock::time_point t_all) {
  const SweepTotals& t = m.t;
  const double within_pct = t.scored ? 100.0 * t.within / t.scored : 0.0;
  const double side_pct = t.side_n ? 100.0 * t.side_ok / t.side_n : 0.0;
  const double tracking_pct = t.scored ? 100.0 * t.tracking / t.scored : 0.0;
  if (json) {
    std::printf("{\"node_within_1_pct\": %.2f, \"side_correct_pct\": %.2f, \"side_decided_tiles\": %d, \"tracking_pct\": %.2f, "
                "\"relocalised_within_tiles\": %d, \"update_ms_10000_nodes\": %.3f, \"update_ms_10000_nodes_p95\": %.3f, "
                "\"update_ms_10000_nodes_max\": %.3f, \"update_cpu_ms_10000_nodes\": %.3f, \"update_cpu_ms_10000_nodes_max\": %.3f, "
                "\"predict_ms_100000_nodes\": %.4f, \"predict_cpu_ms_100000_nodes\": %.4f, \"eq5_node_within_1_pct_at_20pct\": %.2f, "
                "\"paper_table_localised\": %d, \"paper_table_side_correct\": %d, \"scored_tiles\": %d, \"route_nodes\": %zu, "
                "\"route_length_m\": %.0f, \"node_spacing_m\": %.2f, \"swath_m\": %.2f, \"offsets_pct\": [",
                within_pct, side_pct, t.side_n, tracking_pct, m.relocalised, m.upd.mean, m.upd.p95, m.upd.max, m.upd.cpu_mean, m.upd.cpu_max, m.pred_ms,
                m.pred_cpu_ms, m.eq5_within, m.paper_localised, m.paper_side, t.scored, e.meta.size(), e.length_m, e.spacing, e.w.swath_m);
    for (std::size_t i = 0; i < m.pcts.size(); ++i) std::printf("%s%d", i ? ", " : "", m.pcts[i]);
    std::printf("], \"side_correct_pct_of_offset_tiles\": %.2f, \"offset_tiles\": %d, \"dead_reckoned_pct\": %.2f, \"seabeds\": %ld, "
                "\"node_within_1_pct_per_seabed\": [",
                t.off_route ? 100.0 * t.side_ok / t.off_route : 0.0, t.off_route, t.scored ? 100.0 * t.dead_reckoned / t.scored : 0.0, m.seabeds);
    for (std::size_t i = 0; i < t.seed_within.size(); ++i) std::printf("%s%.2f", i ? ", " : "", t.seed_within[i]);
    std::printf("], \"dead_reckoned_offset_tiles\": %d, \"dead_reckoned_cross_track_within_2sigma_pct\": %.2f, \"warmup_tiles\": %d, \"seconds\": %.1f}\n",
                m.dr_n, m.dr_n ? 100.0 * m.dr_in / m.dr_n : 0.0, kWarmupTiles, ms_since(t_all) / 1000.0);
  } else {
    std::printf("node within +/-1: %.1f%% of %d tiles; side correct %.1f%% of %d decided tiles (tracking %.1f%%); re-localised after %d tiles; "
                "update %.2f ms wall / %.2f ms CPU (10,000 nodes); predict %.3f ms wall / %.3f ms CPU (100,000 nodes); eq. 5 model at 20%%: %.1f%%; %.1f s\n",
                within_pct, t.scored, side_pct, t.side_n, tracking_pct, m.relocalised, m.upd.mean, m.upd.cpu_mean, m.pred_ms, m.pred_cpu_ms, m.eq5_within,
                ms_since(t_all) / 1000.0);
  }
}

}  // namespace

int cmd_eval() {
  if (g_opt.multi_pass) return cmd_eval_multi_pass();  // route/experiences.cpp
  if (g_opt.changed_seabed) return cmd_eval_changed_seabed();
  auto e = std::make_unique<EvalRun>();
  e->length_m = g_opt.length_m;
  if (!(e->length_m >= 400.0 && e->length_m <= 20000.0)) return usage("eval", "--length-m: eval needs 400..20000 m");
  const bool json = g_opt.json;
  const bool quick = g_opt.quick;
  EvalSummary m;
  m.seabeds = g_opt.seabeds > 0 ? g_opt.seabeds : quick ? 1 : 3;
  e->out_dir = g_opt.eval_out;
  if (const std::string err = qnav::cli::make_dirs(e->out_dir); !err.empty() || !ensure_dir(e->out_dir)) {
    std::fprintf(stderr, "qnav route eval: %s\n", err.empty() ? ("cannot create " + e->out_dir).c_str() : err.c_str());
    return 1;
  }
  e->log = json ? stderr : stdout;
  const auto t_all = Clock::now();
  Status s = e->w.init(e->length_m, 1);
  if (s) s = e->pipe.init(pipeline::default_route_tile_config());
  if (!s) {
    std::fprintf(stderr, "qnav route eval: %s\n", s.message());
    return 1;
  }
  if (const int rc = teach_eval(*e); rc != 0) return rc;

  // 2. Repeat passes at lateral offsets, forwards and reverse: on this seabed (nodes read from the
  //    route file), then on further seabeds (each taught afresh, nodes in memory).
  m.pcts = quick ? std::vector<int>{0, 20, 40} : std::vector<int>{0, 10, 20, 30, 40, 50};
  std::vector<TileRecord> records;
  std::vector<PassStats> stats;
  std::vector<pipeline::RouteTile> kidnap_src;
  int pass_seed = 100;
  SweepInputs in{&e->pipe, &e->w, &e->train, &e->reader, &e->reader.params(), e->meta_span(), &e->node_along, &m.pcts, 1, e->log};
  s = offset_sweep(in, pass_seed, records, stats, &kidnap_src, &m.eq5_within);
  for (long sb = 2; s && sb <= m.seabeds; ++sb) {
    bool taught = false;
    s = sweep_seabed(*e, sb, m.pcts, pass_seed, records, stats, taught);
    if (!taught) break;
  }
  if (!s) {
    std::fprintf(stderr, "qnav route eval: repeat pass failed: %s\n", s.message());
    return 1;
  }
  m.t = sum_sweep(stats, m.seabeds);
  m.relocalised = kidnapped(*e, kidnap_src);                // 3.
  m.upd = speed_10000(*e, kidnap_src);                      // 4.
  predict_100000(e->spacing, e->log, m.pred_ms, m.pred_cpu_ms);  // 5.
  paper_run(*e, m.paper_localised, m.paper_side);           // 6.
  write_offsets_csv(e->out_dir, m.pcts, stats);
  write_tiles_csv(e->out_dir, records);
  // Is the dead-reckoned cross-track sigma honest? Off-route scored tiles whose offsets came from
  // dead reckoning: the share within 2 sigma of the pass's offset (~95% if sigma is right).
  for (const TileRecord& r : records)
    if (r.tile >= kWarmupTiles && r.pct > 5 && r.st.guidance.offsets == route::OffsetSource::kDeadReckoning) {
      ++m.dr_n;
      m.dr_in += std::abs(r.st.guidance.cross_track_m - r.true_cross_track_m) <= 2.0 * r.st.guidance.cross_track_sigma_m;
    }
  print_eval_summary(*e, m, json, t_all);
  return 0;
}

// qnav route framing: tiles framed in metres, measured. The sonar simulator's survey flown at 2, 5 and
// 15 pings/s and at two speeds with the default tile settings (no flag changed): teach a route, then
// repeat it forwards and in reverse at lateral offsets; node within +/-1 and side correct per
// configuration, against 5 pings/s at 1.5 m/s (the rate and speed the ping-count defaults were tuned
// on, where tiles by distance are the same 90 m every 60 m).
// --trace-sides: every scored tile whose side was decided wrong, with what decided it, and the tiles
// of its pass before it (the registration, its inliers and cross-track against the truth).
void trace_wrong_sides(FILE* log, const std::vector<TileRecord>& records) {
  for (std::size_t i = 0; i < records.size(); ++i) {
    const TileRecord& r = records[i];
    const bool decided = r.tile >= kWarmupTiles && r.want != route::RouteSide::kOnRoute && r.st.guidance.side != route::RouteSide::kUnknown;
    if (!decided || r.st.guidance.side == r.want) continue;
    std::fprintf(log, "  wrong side: offset %d%% %s tile %d\n", r.pct, r.reverse ? "reverse" : "forward", r.tile);
    for (std::size_t j = i >= 4 ? i - 4 : 0; j <= i; ++j) {
      const TileRecord& q = records[j];
      if (q.pct != r.pct || q.reverse != r.reverse) continue;
      const route::GuidanceOutput& g = q.st.guidance;
      std::fprintf(log, "    tile %2d truth %2d est %2d %s p %.2f %-13s offsets %-14s S %2u (est %2u%s, rms %.2f) cross %7.2f (true %6.2f, sigma %.2f) side %-9s want %s%s\n",
                   q.tile, q.truth, q.st.estimate, q.st.confident ? "conf" : "unc ", static_cast<double>(q.st.probability), route::to_string(g.status),
                   route::to_string(g.offsets), q.st.best_inliers, q.st.registration.ok ? q.st.registration.inliers : 0,
                   q.st.via_neighbour ? ", via neighbour" : "", q.st.registration.rms_m, g.cross_track_m, q.true_cross_track_m, g.cross_track_sigma_m,
                   route::to_string(g.side), route::to_string(q.want), g.registration_rejected ? " (registration rejected: disagrees with dead reckoning)" : "");
    }
  }
}

int cmd_framing() {
  const double length_m = g_opt.framing_length_m;
  if (!(length_m >= 400.0 && length_m <= 20000.0)) return usage("framing", "--length-m: framing needs 400..20000 m");
  const bool json = g_opt.json;
  FILE* log = json ? stderr : stdout;
  const auto t_all = Clock::now();
  const double rates[] = {2.0, 5.0, 15.0};
  const double speeds[] = {1.5, 3.0};
  const std::vector<int> pcts = g_opt.quick ? std::vector<int>{20} : std::vector<int>{0, 20, 40};
  struct Row {
    double rate_hz, speed_mps, spacing_m, kp;
    std::size_t nodes;
    int scored, within, side_n, side_ok, rev_scored, rev_within;
    std::uint32_t overflow;
  };
  double only_rate = 0.0, only_speed = 0.0;
  if (!g_opt.framing_only.empty() &&
      (std::sscanf(g_opt.framing_only.c_str(), "%lf:%lf", &only_rate, &only_speed) != 2 || !(only_rate > 0.0) || !(only_speed > 0.0)))
    return usage("framing", "--only: RATE:SPEED, e.g. 2:1.5");
  if (only_rate > 0.0) {
    bool known = false;
    for (double rate : rates)
      for (double speed : speeds) known = known || (rate == only_rate && speed == only_speed);
    if (!known) return usage("framing", "--only: RATE:SPEED must be one of the configurations: 2, 5 or 15 pings/s at 1.5 or 3 m/s");
  }
  const long seabed = g_opt.framing_seabed;
  std::vector<Row> rows;
  Status s;
  for (double rate : rates)
    for (double speed : speeds) {
      if (!s) break;
      const bool is_ref = rate == 5.0 && speed == 1.5;
      if (only_rate > 0.0 && !is_ref && !(rate == only_rate && speed == only_speed)) continue;
      // A pipeline of its own per configuration: the corrector's gain normalisation (EGN) runs on
      // from pass to pass, so with one pipeline a configuration's figures depended on the one before.
      pipeline::RouteTilePipeline pipe;
      s = pipe.init(pipeline::default_route_tile_config());
      if (!s) break;
      pipeline::SimSurvey w;
      s = w.init(length_m, static_cast<std::uint64_t>(seabed));
      if (!s) break;
      if (g_opt.no_speckle) w.sonar.speckle = false;
      if (g_opt.no_ripples) {
        sidescan::SeabedConfig sc = pipeline::default_route_seabed_config(static_cast<std::uint64_t>(seabed));
        sc.ripple_wavelength_m = 0.0f;
        s = w.seabed.init(sc);
        if (!s) break;
      }
      w.route.ping_rate_hz = rate;
      w.route.speed_mps = speed;
      std::vector<pipeline::RouteTile> train;
      s = fly(pipe, w, w.pass(0.0, false, 11), train);
      if (!s || train.size() < 2) {
        if (s) s = Status(StatusCode::kInvalidArgument, "fewer than 2 tiles taught");
        break;
      }
      const double sp = (train.back().node.meta.along_m - train.front().node.meta.along_m) / static_cast<double>(train.size() - 1);
      const route::RouteParams params = pipeline::side_scan_route_params(pipe.config(), sp, w.swath_m);
      std::vector<route::NodeMeta> meta;
      std::vector<double> along;
      double kp = 0.0;
      for (std::size_t i = 0; i < train.size(); ++i) {
        meta.push_back(train[i].node.meta);
        meta.back().index = static_cast<std::uint32_t>(i);
        along.push_back(train[i].truth_along_m);
        kp += static_cast<double>(train[i].node.keypoints.size());
      }
      TileSource src(&train);
      std::fprintf(log, "%.0f pings/s at %.1f m/s (%.2f m between pings): taught %zu nodes (spacing %.1f m, %.1f keypoints/node)\n", rate, speed,
                   speed / rate, train.size(), sp, kp / static_cast<double>(train.size()));
      SweepInputs in{&pipe, &w, &train, &src, &params, Span<const route::NodeMeta>(meta.data(), meta.size()), &along, &pcts, static_cast<int>(seabed), log,
                     g_opt.framing_entry_prior};
      std::vector<TileRecord> records;
      std::vector<PassStats> stats;
      int pass_seed = 100;
      s = offset_sweep(in, pass_seed, records, stats, nullptr, nullptr);
      if (!s) break;
      if (g_opt.trace_sides) trace_wrong_sides(log, records);
      Row r{rate, speed, sp, kp / static_cast<double>(train.size()), train.size(), 0, 0, 0, 0, 0, 0,
            pipe.builder().counters().get(sonar::TileCounter::kTileOverflow)};
      for (const PassStats& p : stats) {
        r.scored += p.scored;
        r.within += p.within1;
        if (p.reverse) {
          r.rev_scored += p.scored;
          r.rev_within += p.within1;
        }
        if (p.pct > 5) {
          r.side_n += p.side_n;
          r.side_ok += p.side_ok;
        }
      }
      rows.push_back(r);
    }
  if (!s) {
    std::fprintf(stderr, "qnav route framing: %s\n", s.message());
    return 1;
  }
  auto pct = [](int a, int b) { return b > 0 ? 100.0 * a / b : 0.0; };
  const Row* ref = nullptr;
  for (const Row& r : rows)
    if (r.rate_hz == 5.0 && r.speed_mps == 1.5) ref = &r;
  if (ref == nullptr) {
    std::fprintf(stderr, "qnav route framing: no configuration matched --only %s\n", g_opt.framing_only.c_str());
    return 1;
  }
  std::fprintf(log, "\npings/s  speed m/s  m/ping  nodes  spacing m  keypoints  node +/-1 %%  (reverse)  side correct %%  vs 5 pings/s 1.5 m/s  tile_overflow\n");
  bool all_within = true;
  for (const Row& r : rows) {
    const double dn = pct(r.within, r.scored) - pct(ref->within, ref->scored), ds = pct(r.side_ok, r.side_n) - pct(ref->side_ok, ref->side_n);
    all_within = all_within && std::abs(dn) <= 2.0 && std::abs(ds) <= 2.0;
    std::fprintf(log, "%7.0f  %9.1f  %6.2f  %5zu  %9.1f  %9.1f  %6.1f (%d)  %9.1f  %8.1f (%d)  %+5.1f / %+5.1f points  %u\n", r.rate_hz, r.speed_mps,
                 r.speed_mps / r.rate_hz, r.nodes, r.spacing_m, r.kp, pct(r.within, r.scored), r.scored, pct(r.rev_within, r.rev_scored),
                 pct(r.side_ok, r.side_n), r.side_n, dn, ds, r.overflow);
  }
  std::fprintf(log, "every configuration within 2 points of 5 pings/s at 1.5 m/s (node +/-1 and side): %s (%.0f s)\n", all_within ? "yes" : "NO",
               ms_since(t_all) / 1000.0);
  if (json) {
    std::printf("{\"length_m\": %.0f, \"offsets_pct\": [", length_m);
    for (std::size_t i = 0; i < pcts.size(); ++i) std::printf("%s%d", i ? ", " : "", pcts[i]);
    std::printf("], \"configurations\": [");
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      std::printf("%s{\"ping_rate_hz\": %.0f, \"speed_mps\": %.1f, \"nodes\": %zu, \"spacing_m\": %.2f, \"keypoints_per_node\": %.1f, "
                  "\"node_within_1_pct\": %.2f, \"scored\": %d, \"reverse_node_within_1_pct\": %.2f, \"side_correct_pct\": %.2f, \"side_decided\": %d, "
                  "\"tile_overflow\": %u}",
                  i ? ", " : "", r.rate_hz, r.speed_mps, r.nodes, r.spacing_m, r.kp, pct(r.within, r.scored), r.scored, pct(r.rev_within, r.rev_scored),
                  pct(r.side_ok, r.side_n), r.side_n, r.overflow);
    }
    std::printf("], \"all_within_2_points\": %s}\n", all_within ? "true" : "false");
  }
  return 0;
}
}  // namespace route_cmd
