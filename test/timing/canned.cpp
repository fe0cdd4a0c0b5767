#include "test/timing/canned.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "drivers/sidescan/sim_seabed.hpp"
#include "drivers/sidescan/sim_sidescan.hpp"
#include "drivers/sidescan/xtf_parser.hpp"
#include "drivers/sidescan/xtf_writer.hpp"
#include "drivers/stereo_sim/mars_yard.hpp"
#include "firmware/pipeline/route_defaults.hpp"
#include "firmware/pipeline/route_experiences.hpp"
#include "firmware/pipeline/vo_defaults.hpp"
#include "nav/core/arena.hpp"
#include "nav/match/geometric_match.hpp"
#include "nav/motion/rigid3d.hpp"
#include "nav/route/camera_tile.hpp"
#include "nav/route/experience.hpp"
#include "nav/route/registration.hpp"
#include "nav/route/route_filter.hpp"
#include "nav/route/route_format.hpp"
#include "nav/route/route_localiser.hpp"
#include "nav/route/tile_features.hpp"
#include "nav/sonar/scanline_corrector.hpp"
#include "nav/sonar/tile_builder.hpp"
#include "nav/vision/descriptor.hpp"
#include "nav/vision/downsample.hpp"
#include "nav/vision/harris.hpp"
#include "nav/vision/rectify.hpp"
#include "nav/vision/stereo.hpp"
#include "nav/vo/stereo_vo.hpp"
#include "test/unit/nav/route/synthetic_route.hpp"

namespace qnav::timing {

void Hash::add(double v) noexcept {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  add(bits);
}

namespace {

void add_pose(Hash& h, const Pose3& p) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) h.add(p.R(r, c));
    h.add(p.t(r));
  }
}

Status first_error(std::initializer_list<Status> all) {
  for (const Status& s : all)
    if (!s.is_ok()) return s;
  return Status::ok();
}

}  // namespace

// ---- VO ----------------------------------------------------------------------------------------------

struct CannedVo::Impl {
  sim::StereoBench bench;
  ImageU8 left[kFrames], right[kFrames];
  Mat3d R_prev_cur[kFrames];  // frame k-1 -> k (true rotation: the attitude sensor)
  Vec3d t_prev_cur[kFrames];
  vo::VoConfig config;
  std::unique_ptr<ArenaStorage> arena;
  vision::HarrisDetector harris;
  std::vector<vision::Corner> corner_storage[kFrames];
  BoundedVector<vision::Corner> corners[kFrames];
  vision::RemapTable remap;
  ImageU8 remapped;
  ImageU8 big, small;  // 1280 x 1024 -> 320 x 256
  vision::OrientedDescriptor descriptor;
  vision::StereoMatcher stereo;
  std::vector<vision::StereoPoint> point_storage;
  BoundedVector<vision::StereoPoint> points;
  std::vector<match::Landmark3> landmarks[2];  // frames 0 and 1, from a VO run at init
  Result<match::GeometricMatcher> fb = Status(StatusCode::kNotReady, "not created"), fc = Status(StatusCode::kNotReady, "not created"),
                                  fast = Status(StatusCode::kNotReady, "not created");
  match::MotionPrior prior;
  std::vector<Vec3d> mp, mc;  // fc matches of frame 0 -> 1
  std::vector<double> w, scratch;
  vo::StereoVo vo;

  vo::VoInput input(int frame) const {
    vo::VoInput in;
    in.left = left[frame].view();
    in.right = right[frame].view();
    if (frame > 0) {
      in.R_prev_cur = R_prev_cur[frame];
      in.has_translation_prior = true;
      in.t_prev_cur_prior_m = 1.1 * t_prev_cur[frame];
      in.t_prior_sigma_m = 0.04;
    }
    return in;
  }
};

CannedVo::CannedVo() : d_(new Impl) {}
CannedVo::~CannedVo() = default;

Status CannedVo::init() {
  Impl& d = *d_;
  const sim::MarsYardTerrain terrain;
  sim::MarsYardTrajectory traj;
  Pose3 cam[kFrames];
  for (int i = 0; i < kFrames; ++i) {
    cam[i] = (i == 0 ? traj.current() : traj.next()).world_T_rover.compose(d.bench.rover_T_left());
    Result<ImageU8> l = ImageU8::allocate(d.bench.width(), d.bench.height());
    Result<ImageU8> r = ImageU8::allocate(d.bench.width(), d.bench.height());
    if (!l || !r) return Status(StatusCode::kCapacityExceeded, "canned VO frames");
    d.left[i] = std::move(l.value());
    d.right[i] = std::move(r.value());
    (void)sim::render_stereo(terrain, d.bench, cam[i], 5 + static_cast<std::uint64_t>(i), d.left[i].view(), d.right[i].view());
    if (i > 0) {
      const Pose3 step = cam[i - 1].inverse().compose(cam[i]);
      d.R_prev_cur[i] = step.R;
      d.t_prev_cur[i] = step.t;
    }
  }
  // The VO benchmark's configuration: 3D-VME, fc matching with fast batches, 300 corners.
  d.config = pipeline::vo_config_for_bench(d.bench);
  d.config.max_corners = 300;
  d.config.mode = vo::VmeMode::k3D;
  d.config.match.score = match::MatchScoreKind::kContinuous;
  d.config.match.fast = true;

  vision::HarrisConfig hc = d.config.harris;
  hc.max_width = d.config.max_width;
  hc.max_height = d.config.max_height;
  hc.max_corners = d.config.max_corners;
  vision::RemapConfig rc;
  rc.max_width = d.config.max_width;
  rc.max_height = d.config.max_height;
  d.arena = std::make_unique<ArenaStorage>(vision::HarrisDetector::arena_bytes(hc) + vo::StereoVo::arena_bytes(d.config) +
                                           vision::RemapTable::arena_bytes(rc));
  const std::size_t n = static_cast<std::size_t>(d.config.max_corners);
  for (int i = 0; i < kFrames; ++i) {
    d.corner_storage[i].resize(n);
    d.corners[i] = BoundedVector<vision::Corner>(Span<vision::Corner>(d.corner_storage[i].data(), n));
  }
  d.point_storage.resize(n);
  d.points = BoundedVector<vision::StereoPoint>(Span<vision::StereoPoint>(d.point_storage.data(), n));
  // A wide-angle lens with barrel distortion (what the rectification LUT undoes on a real camera).
  vision::PinholeRadTan raw;
  raw.fx = raw.fy = d.bench.focal_px();
  raw.cx = d.bench.cu_px();
  raw.cy = d.bench.cv_px();
  raw.k1 = -0.28;
  raw.k2 = 0.07;
  raw.p1 = 0.0005;
  raw.p2 = -0.0003;
  raw.width = d.bench.width();
  raw.height = d.bench.height();
  Result<ImageU8> out = ImageU8::allocate(raw.width, raw.height);
  if (!out) return Status(StatusCode::kCapacityExceeded, "canned remap output");
  d.remapped = std::move(out.value());
  Result<ImageU8> big = ImageU8::allocate(4 * raw.width, 4 * raw.height);
  Result<ImageU8> small = ImageU8::allocate(raw.width, raw.height);
  if (!big || !small) return Status(StatusCode::kCapacityExceeded, "canned downsample images");
  d.big = std::move(big.value());
  d.small = std::move(small.value());
  for (int y = 0; y < d.big.height(); ++y)  // the left frame, each pixel 4 x 4 with a little texture
    for (int x = 0; x < d.big.width(); ++x)
      d.big.view().row(y)[x] = static_cast<std::uint8_t>((d.left[0].view().row(y / 4)[x / 4] + ((x ^ y) & 7)) & 0xff);
  Status s = first_error({d.harris.init(hc, *d.arena), d.remap.init(rc, *d.arena),
                          d.stereo.init(d.config.stereo, d.config.camera), d.vo.init(d.config, *d.arena)});
  if (!s.is_ok()) return s;
  s = d.remap.build_undistort(raw, vision::FlatPortRefraction{});
  if (!s.is_ok()) return s;
  for (int i = 0; i < kFrames; ++i) {
    s = d.harris.detect(d.left[i].view(), d.corners[i]);
    if (!s.is_ok()) return s;
  }
  // Landmarks of frames 0 and 1 as the VO builds them, for the matching and motion stages.
  for (int i = 0; i < 2; ++i) {
    if (!d.vo.process(d.input(i))) return Status(StatusCode::kInvalidArgument, "canned VO frame");
    const Span<const match::Landmark3> l = d.vo.current_landmarks();
    d.landmarks[i].assign(l.begin(), l.end());
  }
  d.prior.R_prev_cur = d.R_prev_cur[1];
  d.prior.t_prev_cur_m = 1.1 * d.t_prev_cur[1];
  d.prior.translation_sigma_m = 0.04;
  match::GeometricMatchConfig mc = d.config.match;
  mc.max_landmarks = n;
  mc.fast = false;
  mc.score = match::MatchScoreKind::kBinary;
  d.fb = match::GeometricMatcher::create(mc);
  mc.score = match::MatchScoreKind::kContinuous;
  d.fc = match::GeometricMatcher::create(mc);
  mc.fast = true;
  d.fast = match::GeometricMatcher::create(mc);
  if (!d.fb || !d.fc || !d.fast) return Status(StatusCode::kInvalidArgument, "canned matchers");
  // The fc matches feed the motion stages.
  Result<Span<const match::Match>> m =
      d.fc->match(Span<const match::Landmark3>(d.landmarks[0].data(), d.landmarks[0].size()),
                  Span<const match::Landmark3>(d.landmarks[1].data(), d.landmarks[1].size()), d.prior);
  if (!m || m->size() < 8) return Status(StatusCode::kInvalidArgument, "canned VO: too few matches");
  for (const match::Match& k : m.value()) {
    const match::Landmark3& a = d.landmarks[0][k.prev];
    const match::Landmark3& b = d.landmarks[1][k.cur];
    d.mp.push_back(a.position_m);
    d.mc.push_back(b.position_m);
    d.w.push_back(1e-4 / (a.sigma_m * a.sigma_m + b.sigma_m * b.sigma_m));
  }
  d.scratch.resize(d.w.size());
  return Status::ok();
}

std::uint64_t CannedVo::harris(int frame) {
  Hash h;
  BoundedVector<vision::Corner>& out = d_->corners[frame];
  if (!d_->harris.detect(d_->left[frame].view(), out).is_ok()) return 0;
  h.add(static_cast<std::uint64_t>(out.size()));
  for (const vision::Corner& c : out) {
    h.add(static_cast<double>(c.x));
    h.add(static_cast<double>(c.y));
  }
  return h.value();
}

std::uint64_t CannedVo::remap(int frame) {
  Hash h;
  if (!d_->remap.apply(d_->left[frame].view(), d_->remapped.view()).is_ok()) return 0;
  const ImageU8& img = d_->remapped;
  for (int y = 0; y < img.height(); y += 17)
    for (int x = 0; x < img.width(); x += 13) h.add(static_cast<std::uint64_t>(img.view().row(y)[x]));
  return h.value();
}

std::uint64_t CannedVo::stereo(int frame) {
  Hash h;
  const BoundedVector<vision::Corner>& c = d_->corners[frame];
  if (!d_->stereo.match(d_->left[frame].view(), d_->right[frame].view(), Span<const vision::Corner>(c.data(), c.size()), d_->points)
           .is_ok())
    return 0;
  h.add(static_cast<std::uint64_t>(d_->points.size()));
  for (const vision::StereoPoint& p : d_->points) h.add(static_cast<double>(p.disparity_px));
  return h.value();
}

std::uint64_t CannedVo::descriptors() {
  Hash h;
  const BoundedVector<vision::Corner>& c = d_->corners[0];
  std::uint64_t valid = 0;
  for (const vision::Corner& k : c) {
    // Corners too near the edge for the support are refused (kOutOfRange): part of the cost.
    if (!vision::compute_oriented_descriptor(d_->left[0].view(), k.x, k.y, 1.0f, d_->descriptor).is_ok()) continue;
    ++valid;
    h.add(static_cast<double>(d_->descriptor.orientation_rad));
    h.add(static_cast<double>(d_->descriptor.v[0]));
  }
  h.add(valid);
  return valid > 0 ? h.value() : 0;
}

std::uint64_t CannedVo::downsample() {
  Hash h;
  if (!vision::downsample(d_->big.view(), 4, d_->small.view()).is_ok()) return 0;
  for (int y = 0; y < d_->small.height(); y += 17)
    for (int x = 0; x < d_->small.width(); x += 13) h.add(static_cast<std::uint64_t>(d_->small.view().row(y)[x]));
  return h.value();
}

namespace {
std::uint64_t run_match(match::GeometricMatcher& m, const std::vector<match::Landmark3>& a,
                        const std::vector<match::Landmark3>& b, const match::MotionPrior& prior) {
  Hash h;
  Result<Span<const match::Match>> r =
      m.match(Span<const match::Landmark3>(a.data(), a.size()), Span<const match::Landmark3>(b.data(), b.size()), prior);
  if (!r) return 0;
  h.add(static_cast<std::uint64_t>(r->size()));
  for (const match::Match& k : r.value()) h.add(static_cast<std::uint64_t>(k.prev) << 16 | k.cur);
  return h.value();
}

std::uint64_t hash_estimate(const Result<motion::RigidEstimate>& e) {
  Hash h;
  if (!e) return 0;
  add_pose(h, e->pose);
  h.add(static_cast<std::uint64_t>(e->inliers));
  return h.value();
}
}  // namespace

std::uint64_t CannedVo::match_fb() { return run_match(d_->fb.value(), d_->landmarks[0], d_->landmarks[1], d_->prior); }
std::uint64_t CannedVo::match_fc() { return run_match(d_->fc.value(), d_->landmarks[0], d_->landmarks[1], d_->prior); }
std::uint64_t CannedVo::match_fast() { return run_match(d_->fast.value(), d_->landmarks[0], d_->landmarks[1], d_->prior); }

std::uint64_t CannedVo::motion_6d() {
  Impl& d = *d_;
  const Span<const Vec3d> p(d.mp.data(), d.mp.size()), c(d.mc.data(), d.mc.size());
  const Span<const double> w(d.w.data(), d.w.size());
  Result<motion::RigidEstimate> e = motion::estimate_rigid_6d(p, c, w);
  if (!e) return 0;
  return hash_estimate(motion::refine_irls_6d(p, c, e.value(), d.config.irls_config, Span<double>(d.scratch.data(), d.scratch.size()), w));
}

std::uint64_t CannedVo::motion_3d() {
  Impl& d = *d_;
  const Span<const Vec3d> p(d.mp.data(), d.mp.size()), c(d.mc.data(), d.mc.size());
  const Span<const double> w(d.w.data(), d.w.size());
  Result<motion::RigidEstimate> e = motion::estimate_translation_3d(p, c, d.R_prev_cur[1], w);
  if (!e) return 0;
  return hash_estimate(motion::refine_irls_3d(p, c, e.value(), d.config.irls_config, Span<double>(d.scratch.data(), d.scratch.size()), w));
}

void CannedVo::vo_reference(int step) {
  d_->vo.reset();
  (void)d_->vo.process(d_->input(step));
}

std::uint64_t CannedVo::vo_step(int step) {
  Hash h;
  Result<vo::VoStep> s = d_->vo.process(d_->input(step + 1));
  if (!s) return 0;
  h.add(static_cast<std::uint64_t>(s->flags));
  h.add(static_cast<std::uint64_t>(s->matches));
  h.add(static_cast<std::uint64_t>(s->inliers));
  add_pose(h, s->prev_T_cur);
  return h.value();
}

// ---- Sonar -------------------------------------------------------------------------------------------

// The default tiles (90 m every 60 m), framed by ping count at the canned 0.3 m per ping: a tile is
// exactly 300 pushes, so tile_prepare() / tile_build() time the push that builds one.
pipeline::RouteTileConfig canned_tile_config() {
  pipeline::RouteTileConfig c = pipeline::default_route_tile_config();
  c.tiles.tile_length_m = 0.0;
  c.tiles.scanlines_per_tile = 300;
  c.tiles.scanline_stride = 200;
  return c;
}

struct CannedSonar::Impl {
  pipeline::RouteTileConfig config = canned_tile_config();
  sidescan::SideScanSimConfig sim_config = pipeline::default_route_sonar_config();
  sidescan::Seabed seabed;
  sidescan::SideScanSimulator sim;
  std::unique_ptr<ArenaStorage> arena;
  sonar::ScanlineCorrector corrector;
  sonar::TileBuilder tiles;
  route::TileFeatureExtractor features;
  std::vector<float> port[kPings], stbd[kPings];
  std::vector<float> work_port, work_stbd;
  std::vector<std::uint8_t> xtf_header_bytes;
  std::vector<std::uint8_t> xtf_packets[kPings];
  sidescan::XtfFileHeader xtf_header;
  sidescan::XtfPing xtf_ping;
  sonar::CorrectedScanline line;
  route::RouteNode node;
  int pushed = 0;
  bool tile_ready = false;  // a tile has been built (by the sonar_tile stage or features_prepare)

  static constexpr double kPingSpacingM = 0.3;  // 1.5 m/s at 5 Hz
  sonar::SonarPing ping(const std::vector<float>& p, const std::vector<float>& s, std::uint32_t number) const {
    sonar::SonarPing out;
    out.ping_number = number;
    out.port = Span<const float>(p.data(), p.size());
    out.stbd = Span<const float>(s.data(), s.size());
    out.slant_range_m = sim_config.slant_range_m;
    out.altitude_m = -1.0f;  // bottom detection
    return out;
  }
  Status simulate(std::uint32_t k, std::vector<float>& p, std::vector<float>& s) {
    const std::size_t n = static_cast<std::size_t>(sim_config.samples_per_side);
    p.resize(n);
    s.resize(n);
    return sim.ping(Pose2{kPingSpacingM * k, 0.0, 0.0}, 8.0f, k, Span<float>(p.data(), n), Span<float>(s.data(), n));
  }
  Status push(std::uint32_t k, bool& built) {
    Status s = simulate(k, work_port, work_stbd);
    if (s.is_ok()) s = corrector.correct(ping(work_port, work_stbd, k), line);
    if (!s.is_ok()) return s;
    Result<bool> r = tiles.push(line, Pose2{kPingSpacingM * k, 0.0, 0.0});
    if (!r) return r.status();
    built = r.value();
    return Status::ok();
  }
};

CannedSonar::CannedSonar() : d_(new Impl) {}
CannedSonar::~CannedSonar() = default;

Status CannedSonar::init() {
  Impl& d = *d_;
  d.arena = std::make_unique<ArenaStorage>(sonar::ScanlineCorrector::arena_bytes(d.config.corrector) +
                                           sonar::TileBuilder::arena_bytes(d.config.tiles) +
                                           route::TileFeatureExtractor::arena_bytes(d.config.features));
  Status s = first_error({d.seabed.init(pipeline::default_route_seabed_config(7)), d.sim.init(d.sim_config, &d.seabed),
                          d.corrector.init(d.config.corrector, *d.arena), d.tiles.init(d.config.tiles, *d.arena),
                          d.features.init(d.config.features, *d.arena)});
  for (int k = 0; k < kPings && s.is_ok(); ++k) s = d.simulate(static_cast<std::uint32_t>(k * 37), d.port[k], d.stbd[k]);
  if (!s.is_ok()) return s;
  // The same pings as XTF packets, for the decoder.
  d.xtf_header_bytes.resize(sidescan::kXtfFileHeaderBytes);
  s = sidescan::encode_xtf_file_header(Span<std::uint8_t>(d.xtf_header_bytes.data(), d.xtf_header_bytes.size()), 0, "TIMING");
  if (!s.is_ok()) return s;
  Result<sidescan::XtfFileHeader> hdr =
      sidescan::parse_xtf_file_header(Span<const std::uint8_t>(d.xtf_header_bytes.data(), d.xtf_header_bytes.size()));
  if (!hdr) return hdr.status();
  d.xtf_header = hdr.value();
  const std::size_t n = d.port[0].size();
  for (int k = 0; k < kPings; ++k) {
    sidescan::XtfWritePing w;
    w.ping_number = static_cast<std::uint32_t>(k);
    w.slant_range_m = d.sim_config.slant_range_m;
    w.altitude_m = 8.0f;
    w.port = Span<const float>(d.port[k].data(), n);
    w.stbd = Span<const float>(d.stbd[k].data(), n);
    w.sample_scale = 4.0f;
    d.xtf_packets[k].resize(sidescan::xtf_ping_bytes(n));
    Result<std::size_t> r = sidescan::encode_xtf_ping(Span<std::uint8_t>(d.xtf_packets[k].data(), d.xtf_packets[k].size()), w);
    if (!r) return r.status();
  }
  d.work_port.resize(n);
  d.work_stbd.resize(n);
  return Status::ok();
}

std::uint64_t CannedSonar::xtf_decode(int k) {
  Impl& d = *d_;
  Hash h;
  const std::vector<std::uint8_t>& p = d.xtf_packets[k];
  if (!sidescan::parse_xtf_sonar_ping(Span<const std::uint8_t>(p.data(), p.size()), d.xtf_header, d.xtf_ping,
                                      Span<float>(d.work_port.data(), d.work_port.size()),
                                      Span<float>(d.work_stbd.data(), d.work_stbd.size()))
           .is_ok())
    return 0;
  h.add(static_cast<std::uint64_t>(d.xtf_ping.ping_number));
  h.add(static_cast<double>(d.work_port[100]));
  h.add(static_cast<double>(d.work_stbd[400]));
  return h.value();
}

std::uint64_t CannedSonar::scanline(int k) {
  Hash h;
  if (!d_->corrector.correct(d_->ping(d_->port[k], d_->stbd[k], static_cast<std::uint32_t>(k)), d_->line).is_ok()) return 0;
  h.add(static_cast<double>(d_->line.altitude_m));
  return h.value();
}

void CannedSonar::tile_prepare() {
  Impl& d = *d_;
  d.tiles.reset();
  bool built = false;
  for (d.pushed = 0; d.pushed + 1 < d.config.tiles.scanlines_per_tile; ++d.pushed)
    if (!d.push(static_cast<std::uint32_t>(d.pushed), built).is_ok() || built) return;
  // The last scanline is simulated and corrected here, so tile_build() counts the push alone.
  (void)d.simulate(static_cast<std::uint32_t>(d.pushed), d.work_port, d.work_stbd);
  (void)d.corrector.correct(d.ping(d.work_port, d.work_stbd, static_cast<std::uint32_t>(d.pushed)), d.line);
}

std::uint64_t CannedSonar::tile_build() {
  Impl& d = *d_;
  Hash h;
  Result<bool> r = d.tiles.push(d.line, Pose2{Impl::kPingSpacingM * d.pushed, 0.0, 0.0});
  if (!r || !r.value()) return 0;
  d.tile_ready = true;
  const sonar::SonarTile& t = d.tiles.tile();
  h.add(static_cast<std::uint64_t>(t.scanlines));
  for (int y = 0; y < t.intensity.height(); y += 29)
    for (int x = 0; x < t.intensity.width(); x += 31) h.add(static_cast<double>(t.intensity.row(y)[x]));
  return h.value();
}

// `timing_stages tile_features` alone (no sonar_tile before it) would extract from an empty tile and
// fail; the tile is built here, outside the counted region, so the stage counts the same either way.
void CannedSonar::features_prepare() {
  if (d_->tile_ready) return;
  tile_prepare();
  (void)tile_build();
}

std::uint64_t CannedSonar::tile_features() {
  Impl& d = *d_;
  Hash h;
  const sonar::SonarTile& t = d.tiles.tile();
  route::TileGeometry g;
  g.resolution_m = t.resolution_m;
  g.origin_north_m = t.origin_north_m;
  g.origin_east_m = t.origin_east_m;
  if (!d.features.extract(t.intensity, t.coverage, g, d.node).is_ok()) return 0;
  h.add(static_cast<std::uint64_t>(d.node.keypoints.size()));
  for (const route::RouteKeypoint& k : d.node.keypoints) {
    h.add(static_cast<double>(k.x_m));
    h.add(static_cast<double>(k.y_m));
  }
  return h.value();
}

// ---- Route -------------------------------------------------------------------------------------------

namespace {

constexpr double kSpacingM = 60.0;

// Experience record r: node r / per_node, the seabed under it seen again from 8 m to the side per slot
// (another pass's view, its own noise and keypoint selection), in the node's frame.
class RepeatingExperienceSource final : public route::NodeSource {
 public:
  RepeatingExperienceSource(const route::testing::SyntheticWorld* w, std::uint32_t nodes, std::uint32_t per_node, double spacing_m)
      : world_(w), nodes_(nodes), per_node_(per_node), spacing_m_(spacing_m) {}
  std::uint32_t node_count() const noexcept override { return nodes_ * per_node_; }
  Status load(std::uint32_t r, route::RouteNode& out) noexcept override {
    const std::uint32_t node = r / per_node_, slot = r % per_node_;
    out = world_->observe(Pose2{30.0 + spacing_m_ * (node % 30), 8.0 * (slot + 1), 0.0}, 45.0, 49.0, 0.3, 0.8, 128, 7000 + r, 20);
    for (route::RouteKeypoint& k : out.keypoints) k.y_m += static_cast<float>(8.0 * (slot + 1));  // into the node's frame
    out.meta = route::NodeMeta{};
    out.meta.index = node;
    return Status::ok();
  }

 private:
  const route::testing::SyntheticWorld* world_;
  std::uint32_t nodes_, per_node_;
  double spacing_m_;
};

// The flight localiser's nodes come from the route file: a load is a record read and decoded
// (route_format's decode_node: CRC, byte order, field checks). The synthetic route sources generate
// each node instead (a pass over the world's landmarks, a log, a cos and a lround per term: about a
// third of a counted update on LEON3, test input, not flight code). This source stands in for the
// file: a recording pass before the counted calls (init) encodes every node the counted updates load
// into route records, and a counted load decodes its record; the nodes are the same bit for bit (the
// record holds x, y, score as float and the descriptors as bytes; the tiles' headings are 0), so the
// updates and their hashes are too. A node not recorded is generated and counted (misses(): the
// route stages fail, hash 0, if any of their loads was generated inside the counted call).
class RecordedNodeSource final : public route::NodeSource {
 public:
  explicit RecordedNodeSource(route::NodeSource* inner) : inner_(inner) {
    params_.sensor = route::SensorKind::kSideScan;
    params_.max_keypoints = static_cast<std::uint16_t>(route::kMaxKeypointsPerNode);
    params_.node_spacing_m = static_cast<float>(kSpacingM);
    params_.tile_length_m = 90.0f;
    params_.tile_width_m = 98.0f;
    params_.pixel_m = 0.1f;
  }
  std::uint32_t node_count() const noexcept override { return inner_->node_count(); }
  Status load(std::uint32_t i, route::RouteNode& out) noexcept override {
    const std::size_t n = route::record_bytes(params_.max_keypoints);
    const auto it = std::lower_bound(index_.begin(), index_.end(), i);
    if (it != index_.end() && *it == i) {
      const std::size_t r = static_cast<std::size_t>(it - index_.begin());
      return route::decode_node(params_, Span<const std::uint8_t>(records_.data() + r * n, n), stored_index_[r], out, nullptr);
    }
    QNAV_RETURN_IF_ERROR(inner_->load(i, out));
    if (!recording_) ++misses_;
    if (recording_) {  // insert in index order (before the counted calls only)
      const std::size_t r = static_cast<std::size_t>(it - index_.begin());
      index_.insert(index_.begin() + static_cast<std::ptrdiff_t>(r), i);
      stored_index_.insert(stored_index_.begin() + static_cast<std::ptrdiff_t>(r), out.meta.index);
      records_.insert(records_.begin() + static_cast<std::ptrdiff_t>(r * n), n, 0);
      QNAV_RETURN_IF_ERROR(route::encode_node(params_, out, Span<std::uint8_t>(records_.data() + r * n, n)));
    }
    return Status::ok();
  }
  void set_recording(bool on) { recording_ = on; }
  std::size_t misses() const { return misses_; }  // loads generated outside the recording pass

 private:
  route::NodeSource* inner_;
  route::RouteParams params_;
  std::vector<std::uint32_t> index_;  // sorted
  std::vector<std::uint32_t> stored_index_;  // the node index each record holds (an experience record: its node's)
  std::vector<std::uint8_t> records_;  // one record per index_ entry, same order
  bool recording_ = false;
  std::size_t misses_ = 0;
};

}  // namespace

struct CannedRoute::Impl {
  route::testing::SyntheticWorld world{1900.0, 200.0, 0.008, 3};
  route::testing::RepeatingRouteSource generated{&world, kRouteNodes, kSpacingM};
  RecordedNodeSource source{&generated};
  std::vector<route::NodeMeta> meta;
  route::LocaliserConfig config = pipeline::default_localiser_config(route::RouteDirection::kForward, kRouteNodes);
  route::RouteParams params;
  std::unique_ptr<ArenaStorage> arena;
  route::RouteLocaliser localiser;
  route::Registrar registrar;
  route::RouteNode pair_a[3], pair_b[3];
  route::RouteNode sensed[kUpdates];
  route::RegistrationResult registration;
  route::LocaliserStep step;
  route::RouteFilterConfig big_filter_config;
  std::unique_ptr<ArenaStorage> big_filter_arena;
  route::RouteFilter big_filter;
  route::LocaliserConfig exp_config = with_experiences(config);
  std::unique_ptr<ArenaStorage> exp_arena;
  route::RouteLocaliser exp_localiser;
  route::ExperienceIndex exp_index;
  RepeatingExperienceSource exp_generated{&world, kRouteNodes, kExperiencesPerNode, kSpacingM};
  RecordedNodeSource exp_source{&exp_generated};
  static route::LocaliserConfig with_experiences(route::LocaliserConfig c) {
    pipeline::enable_experiences(c, kExperiencesPerNode);
    return c;
  }
  route::CameraTileProjector projector;
  route::CameraTileConfig camera_config;
  ImageU8 camera_image;
  std::vector<float> raster;
  std::vector<std::uint8_t> coverage;
};

CannedRoute::CannedRoute() : d_(new Impl) {}
CannedRoute::~CannedRoute() = default;

Status CannedRoute::init() {
  Impl& d = *d_;
  d.meta.resize(kRouteNodes);
  for (std::uint32_t i = 0; i < kRouteNodes; ++i) {
    d.meta[i].index = i;
    d.meta[i].pose = Pose2{30.0 + kSpacingM * i, 0.0, 0.0};
    d.meta[i].along_m = kSpacingM * i;
  }
  d.params.sensor = route::SensorKind::kSideScan;
  d.params.node_spacing_m = static_cast<float>(kSpacingM);
  d.arena = std::make_unique<ArenaStorage>(route::RouteLocaliser::arena_bytes(d.config) + route::Registrar::arena_bytes(d.config.registration));
  d.big_filter_config = d.config.filter;
  d.big_filter_config.max_nodes = 100000;
  d.big_filter_arena = std::make_unique<ArenaStorage>(route::RouteFilter::arena_bytes(d.big_filter_config));
  Status s = first_error({d.localiser.init(d.config, *d.arena), d.registrar.init(d.config.registration, *d.arena),
                          d.projector.init(d.camera_config), d.big_filter.init(d.big_filter_config, *d.big_filter_arena)});
  if (!s.is_ok()) return s;
  d.exp_arena = std::make_unique<ArenaStorage>(route::RouteLocaliser::arena_bytes(d.exp_config) +
                                               route::ExperienceIndex::arena_bytes(kRouteNodes, kExperiencesPerNode));
  QNAV_RETURN_IF_ERROR(d.exp_localiser.init(d.exp_config, *d.exp_arena));
  QNAV_RETURN_IF_ERROR(d.exp_index.init(kRouteNodes, kExperiencesPerNode, *d.exp_arena));
  QNAV_RETURN_IF_ERROR(d.exp_index.reset(kRouteNodes));
  for (std::uint32_t r = 0; r < kRouteNodes * kExperiencesPerNode; ++r) {
    route::ExperienceMeta m;
    m.record = r;
    m.node = r / kExperiencesPerNode;
    m.slot = static_cast<std::uint16_t>(r % kExperiencesPerNode);
    m.pass_id = 1 + m.slot;
    m.offset_m = static_cast<float>(8.0 * (m.slot + 1));
    QNAV_RETURN_IF_ERROR(d.exp_index.set(m));
  }
  for (int k = 0; k < 3; ++k) {
    d.pair_a[k] = d.world.observe(Pose2{300.0 + 200.0 * k, 12.0, 0.02}, 45.0, 49.0, 0.3, 0.8, 128, 1 + 2 * static_cast<std::uint64_t>(k), 20);
    d.pair_b[k] = d.world.observe(Pose2{310.0 + 200.0 * k, 0.0, 0.0}, 45.0, 49.0, 0.3, 0.8, 128, 2 + 2 * static_cast<std::uint64_t>(k), 20);
  }
  for (int k = 0; k < kUpdates; ++k)
    d.sensed[k] = d.world.observe(Pose2{30.0 + kSpacingM * (5 + 7 * k) + 10.0, 15.0, 0.0}, 45.0, 49.0, 0.3, 0.8, 128,
                                  50 + static_cast<std::uint64_t>(k), 20);
  // A 320 x 256 downward image of a pseudo-random texture, seen from 2 m.
  Result<ImageU8> img = ImageU8::allocate(320, 256);
  if (!img) return img.status();
  d.camera_image = std::move(img.value());
  std::uint32_t x = 12345;
  for (int r = 0; r < 256; ++r)
    for (int c = 0; c < 320; ++c) {
      x = x * 1664525u + 1013904223u;
      d.camera_image.view().row(r)[c] = static_cast<std::uint8_t>(64 + ((x >> 24) & 0x7f) + ((r / 16 + c / 16) % 2) * 32);
    }
  d.raster.assign(static_cast<std::size_t>(d.camera_config.width_px * d.camera_config.height_px), 0.0f);
  d.coverage.assign(d.raster.size(), 0);
  // The recording pass (RecordedNodeSource): every counted update run once, its loads encoded.
  d.source.set_recording(true);
  d.exp_source.set_recording(true);
  for (int k = 0; k < kUpdates; ++k) {
    route_restart();
    (void)route_update(k);
    route_restart_exp();
    (void)route_update_exp(k);
  }
  d.source.set_recording(false);
  d.exp_source.set_recording(false);
  return Status::ok();
}

std::uint64_t CannedRoute::registration(int k) {
  Hash h;
  if (!d_->registrar.register_tile(d_->pair_a[k], d_->pair_b[k], d_->registration).is_ok()) return 0;
  h.add(static_cast<std::uint64_t>(d_->registration.inliers));
  h.add(d_->registration.sensed_to_node.x_m);
  h.add(d_->registration.sensed_to_node.y_m);
  return h.value();
}

void CannedRoute::route_restart() {
  (void)d_->localiser.start(d_->params, Span<const route::NodeMeta>(d_->meta.data(), d_->meta.size()), d_->source);
}

std::uint64_t CannedRoute::route_update(int k) {
  Hash h;
  if (!d_->localiser.step(d_->sensed[k], kSpacingM, d_->step).is_ok() || d_->source.misses() != 0) return 0;
  h.add(static_cast<std::uint64_t>(d_->step.estimate));
  h.add(static_cast<std::uint64_t>(d_->step.registrations));
  h.add(static_cast<double>(d_->step.probability));
  h.add(d_->step.mass_pm1);
  return h.value();
}

void CannedRoute::route_restart_exp() {
  Impl& d = *d_;
  (void)d.exp_localiser.start(d.params, Span<const route::NodeMeta>(d.meta.data(), d.meta.size()), d.source);
  (void)d.exp_localiser.attach_experiences(&d.exp_index, &d.exp_source);
}

std::uint64_t CannedRoute::route_update_exp(int k) {
  Hash h;
  if (!d_->exp_localiser.step(d_->sensed[k], kSpacingM, d_->step).is_ok() || d_->source.misses() != 0 || d_->exp_source.misses() != 0)
    return 0;
  if (d_->step.experience_registrations == 0) return 0;  // the stage is meant to register experiences
  h.add(static_cast<std::uint64_t>(d_->step.estimate));
  h.add(static_cast<std::uint64_t>(d_->step.registrations));
  h.add(static_cast<std::uint64_t>(d_->step.experience_registrations));
  h.add(static_cast<double>(d_->step.probability));
  h.add(d_->step.mass_pm1);
  return h.value();
}

void CannedRoute::predict_reset() { (void)d_->big_filter.reset(100000, kSpacingM); }

std::uint64_t CannedRoute::predict_100k() {
  Hash h;
  if (!d_->big_filter.predict(kSpacingM).is_ok()) return 0;
  h.add(static_cast<std::uint64_t>(d_->big_filter.argmax()) + 1);
  return h.value();
}

std::uint64_t CannedRoute::camera_tile(int k) {
  Impl& d = *d_;
  Hash h;
  const route::CameraIntrinsics K{300.0, 300.0, 159.5, 127.5};
  Mat3d body_R_cam;
  body_R_cam << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const double heading = 0.4 + 1.7 * k;
  const Pose3 cam{rotation_from_rpy(0.03, -0.02, heading) * body_R_cam, Vec3d(10.0, 5.0, -2.0)};
  const int w = d.camera_config.width_px, ht = d.camera_config.height_px;
  route::TileGeometry g;
  Result<double> cov = d.projector.project(d.camera_image.view(), K, cam, 0.0, heading, ImageViewF32::make(d.raster.data(), w, ht).value(),
                                           ImageViewU8::make(d.coverage.data(), w, ht).value(), g);
  if (!cov) return 0;
  h.add(cov.value());
  for (std::size_t i = 0; i < d.raster.size(); i += 97) h.add(static_cast<double>(d.raster[i]));
  return h.value();
}

}  // namespace qnav::timing
