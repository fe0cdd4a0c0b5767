// A camera frame to the VO front end: the bytes as a PGM file replayed by hal/sim's PgmSequenceCamera
// (the camera replay backend), the captured frame -> nav/vision HarrisDetector + oriented descriptors
// at the corners, and as a stereo pair (right = left shifted by the disparity in the last byte) twice
// through nav/vo StereoVo (Harris, ZNCC stereo, geometric matching, motion, track refinement) with the
// VO configuration of the simulated bench (pipeline::vo_config_for_bench, as test/timing/canned does).
// Frames larger than the configured 320 x 256 must be refused, not read out of bounds.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "drivers/stereo_sim/mars_yard.hpp"
#include "firmware/pipeline/vo_defaults.hpp"
#include "hal/sim/pgm_sequence_camera.hpp"
#include "nav/core/arena.hpp"
#include "nav/vision/descriptor.hpp"
#include "nav/vision/harris.hpp"
#include "nav/vo/stereo_vo.hpp"
#include "test/fuzz/fuzz_support.hpp"

int qnav_fuzz_vo_chain(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  if (size < 2) return 0;
  const int disparity = 8 + data[size - 1] % 28;
  const std::string dir = fuzz::scratch_dir();
  fuzz::write_scratch("vo_0.pgm", data, size - 1);
  const std::string pattern = dir + "/vo_%d.pgm";
  hal::PgmSequenceConfig pc;
  pc.pattern = pattern.c_str();
  pc.count = 1;
  hal::PgmSequenceCamera camera;
  if (!camera.open(pc)) return 0;
  const hal::CameraFormat f = camera.format();
  if (f.width <= 0 || f.height <= 0 || static_cast<long>(f.width) * f.height > (1l << 20)) return 0;
  Result<ImageU8> left = ImageU8::allocate(f.width, f.height);
  Result<ImageU8> right = ImageU8::allocate(f.width, f.height);
  Result<ImageU8> next_left = ImageU8::allocate(f.width, f.height);
  Result<ImageU8> next_right = ImageU8::allocate(f.width, f.height);
  if (!left || !right || !next_left || !next_right) return 0;
  if (!camera.capture(left->view(), 0)) return 0;
  // The pair and the next pair (the scene moved one pixel right and down).
  for (int y = 0; y < f.height; ++y) {
    const std::uint8_t* l = left->view().row(y);
    const std::uint8_t* above = left->view().row(y > 0 ? y - 1 : 0);
    for (int x = 0; x < f.width; ++x) next_left->view().row(y)[x] = above[x > 0 ? x - 1 : 0];
    const std::uint8_t* nl = next_left->view().row(y);
    for (int x = 0; x < f.width; ++x) {
      const int xs = x + disparity < f.width ? x + disparity : f.width - 1;
      right->view().row(y)[x] = l[xs];
      next_right->view().row(y)[x] = nl[xs];
    }
  }

  const sim::StereoBench bench;
  vo::VoConfig config = pipeline::vo_config_for_bench(bench);
  config.max_corners = 120;
  vision::HarrisConfig hc = config.harris;
  hc.max_width = config.max_width;
  hc.max_height = config.max_height;
  hc.max_corners = config.max_corners;
  ArenaStorage arena(vision::HarrisDetector::arena_bytes(hc) + vo::StereoVo::arena_bytes(config));
  vision::HarrisDetector harris;
  vo::StereoVo odometry;
  if (!arena.valid() || !harris.init(hc, arena) || !odometry.init(config, arena)) __builtin_trap();  // fixed configuration

  std::vector<vision::Corner> storage(static_cast<std::size_t>(config.max_corners));
  BoundedVector<vision::Corner> corners(Span<vision::Corner>(storage.data(), storage.size()));
  const Status h = harris.detect(left->view(), corners);
  if (h.is_ok()) {
    vision::OrientedDescriptor d;
    for (const vision::Corner& c : corners) {
      if (!(c.x >= 0.0f && c.y >= 0.0f && c.x < static_cast<float>(f.width) && c.y < static_cast<float>(f.height))) __builtin_trap();
      (void)vision::compute_oriented_descriptor(left->view(), c.x, c.y, 1.0f, d);
    }
  }
  vo::VoInput in;
  in.left = left->view();
  in.right = right->view();
  (void)odometry.process(in);
  in.left = next_left->view();
  in.right = next_right->view();
  in.stamp_ns = 100000000;
  (void)odometry.process(in);
  return 0;
}

static void seeds_vo_chain(qnav::fuzz::Seeds& out) {
  using namespace qnav;
  // A rendered Mars-yard frame of the simulated bench (320 x 256) as PGM, and a small textured one.
  const sim::StereoBench bench;
  const sim::MarsYardTerrain terrain;
  sim::MarsYardTrajectory traj;
  Result<ImageU8> l = ImageU8::allocate(bench.width(), bench.height());
  Result<ImageU8> r = ImageU8::allocate(bench.width(), bench.height());
  if (l && r) {
    const Pose3 cam = traj.current().world_T_rover.compose(bench.rover_T_left());
    (void)sim::render_stereo(terrain, bench, cam, 5, l->view(), r->view());
    std::string pgm = "P5\n" + std::to_string(bench.width()) + " " + std::to_string(bench.height()) + "\n255\n";
    for (int y = 0; y < bench.height(); ++y) pgm.append(reinterpret_cast<const char*>(l->view().row(y)), static_cast<std::size_t>(bench.width()));
    out.push_back(fuzz::Seed{"mars-yard-320x256.pgm", pgm + '\x14'});
  }
  std::string small = "P5\n48 40\n255\n";
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 48; ++x) small += static_cast<char>(((x / 6 + y / 5) % 2) * 200 + (x * y) % 37);
  out.push_back(fuzz::Seed{"checker-48x40.pgm", small + '\x0c'});
}
QNAV_FUZZ_TARGET(vo_chain, 6)
