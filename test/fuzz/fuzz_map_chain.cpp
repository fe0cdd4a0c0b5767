// Downward-camera frames through nav/topo HomographyChain (the chain `qnav map` runs): the bytes give
// a 128 x 96 seabed texture (repeated when short) and a motion (shift, rotation, scale per frame, an
// altitude); 2 to 5 frames are the texture moved by that motion, and every one goes through
// process(). Whatever the frames hold (flat, saturated, noise, repeats), the chain must not crash, its
// pose must stay finite, and a refused frame must leave the pose exactly as it was.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "nav/core/arena.hpp"
#include "nav/core/image.hpp"
#include "nav/topo/homography_chain.hpp"
#include "test/fuzz/fuzz_support.hpp"

namespace {
constexpr int kW = 128, kH = 96;
}

int qnav_fuzz_map_chain(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  if (size < 8) return 0;
  const double dx = static_cast<std::int8_t>(data[0]) / 8.0, dy = static_cast<std::int8_t>(data[1]) / 8.0;
  const double rot = static_cast<std::int8_t>(data[2]) * 0.002;  // up to ~15 deg per frame
  const double scale = 1.0 + static_cast<std::int8_t>(data[3]) / 1024.0;
  const double altitude = data[4] == 0 ? -1.0 : data[4] / 16.0;
  const int frames = 2 + data[5] % 4;
  const std::uint8_t* tex = data + 6;
  const std::size_t tex_n = size - 6;
  static std::vector<std::uint8_t> pixels(static_cast<std::size_t>(kW) * kH);
  topo::HomographyChainConfig config;
  config.max_width = kW;
  config.max_height = kH;
  config.corners_per_level = 150;
  config.max_keypoints = 150;
  config.camera.fx = config.camera.fy = 120.0;
  static ArenaStorage arena(topo::HomographyChain::arena_bytes(config));
  static topo::HomographyChain chain;
  static bool ready = false;
  if (!ready) {
    if (!arena.valid() || !chain.init(config, arena)) __builtin_trap();  // a fixed, valid configuration
    ready = true;
  }
  chain.reset();
  for (int f = 0; f < frames; ++f) {
    // Frame f: the texture seen through the motion applied f times (nearest neighbour, wrapping).
    const double a = rot * f, s = std::pow(scale, f), c = std::cos(a) * s, sn = std::sin(a) * s;
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) {
        const double u = c * (x - kW / 2) - sn * (y - kH / 2) + kW / 2 + dx * f;
        const double v = sn * (x - kW / 2) + c * (y - kH / 2) + kH / 2 + dy * f;
        const long iu = static_cast<long>(std::floor(u)), iv = static_cast<long>(std::floor(v));
        const std::size_t k = static_cast<std::size_t>(((iv % kH + kH) % kH) * kW + ((iu % kW + kW) % kW));
        pixels[static_cast<std::size_t>(y) * kW + static_cast<std::size_t>(x)] = tex[k % tex_n];
      }
    }
    const topo::ChainPose before = chain.pose();
    topo::ChainStep step;
    const Status st = chain.process(ConstImageViewU8::make(pixels.data(), kW, kH).value(), altitude, step);
    if (!st) __builtin_trap();  // only misuse is a Status
    const topo::ChainPose& p = chain.pose();
    if (!p.H_0_cur.allFinite() || !p.position_px.allFinite() || !std::isfinite(p.heading_rad) || !std::isfinite(p.scale)) __builtin_trap();
    if (step.status != topo::StepStatus::kOk &&
        (p.H_0_cur != before.H_0_cur || p.position_px != before.position_px || p.heading_rad != before.heading_rad))
      __builtin_trap();  // a refused frame must leave the pose intact
  }
  return 0;
}

static void seeds_map_chain(qnav::fuzz::Seeds& out) {
  // A smooth random texture under a few motions, and a flat one.
  std::string tex(static_cast<std::size_t>(kW) * kH, '\0');
  std::uint32_t r = 12345;
  for (std::size_t i = 0; i < tex.size(); ++i) {
    r = r * 1664525u + 1013904223u;
    const int x = static_cast<int>(i % kW), y = static_cast<int>(i / kW);
    const double v = 128.0 + 50.0 * std::sin(x * 0.31) * std::cos(y * 0.23) + 30.0 * std::sin((x + 2 * y) * 0.11) + ((r >> 24) % 40) - 20.0;
    tex[i] = static_cast<char>(static_cast<unsigned char>(static_cast<int>(v < 0 ? 0 : (v > 255 ? 255 : v))));
  }
  // signed char: plain char is unsigned on ARM.
  const signed char motions[][6] = {{8, 0, 0, 0, 32, 2}, {-6, 5, 5, 0, 0, 3}, {3, -3, -10, 6, 40, 1}, {0, 0, 0, 0, 16, 0}};
  int k = 0;
  for (const auto& m : motions)
    out.push_back(qnav::fuzz::Seed{"motion" + std::to_string(k++), std::string(reinterpret_cast<const char*>(m), 6) + tex});
  out.push_back(qnav::fuzz::Seed{"flat", std::string("\x08\x00\x00\x00\x20\x02", 6) + std::string(512, '\x80')});
}
QNAV_FUZZ_TARGET(map_chain, 4)
