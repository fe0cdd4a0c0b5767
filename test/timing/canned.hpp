// Canned, deterministic inputs for every stage of the static pipeline, and one call of each stage on
// them: what the timing tests count instructions of on each target (test/timing/timing_stages.cpp),
// and what the freestanding LEON3 image runs (test/timing/freestanding). Pure code: nav/ and the
// simulators (drivers/stereo_sim, drivers/sidescan), no OS. init() renders the inputs and sizes every
// buffer (heap allowed there, as at a daemon's start-up); the stage calls allocate nothing.
//
// Every call returns a 64-bit hash of its results (FNV-1a over integers and the bit patterns of the
// doubles), so a target that computes different numbers gives a different hash.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "nav/core/status.hpp"

namespace qnav::timing {

// FNV-1a over values, not memory bytes: the same on little- and big-endian targets.
class Hash {
 public:
  void add(std::uint64_t v) noexcept {
    for (int i = 0; i < 8; ++i) {
      h_ ^= (v >> (8 * i)) & 0xffu;
      h_ *= 0x100000001b3ull;
    }
  }
  void add(double v) noexcept;
  std::uint64_t value() const noexcept { return h_; }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ull;
};

// Harris, remap, stereo, fb/fc/fast matching, 6D and 3D motion and whole VO steps on rendered
// Mars-yard stereo frames at 320x256 (the VO benchmark's scene and configuration, 300 corners).
class CannedVo {
 public:
  static constexpr int kFrames = 3;  // two VO steps: 0 -> 1 and 1 -> 2
  CannedVo();
  ~CannedVo();
  Status init();
  std::uint64_t harris(int frame);   // corners of frame's left image
  std::uint64_t remap(int frame);    // undistortion table applied to frame's left image
  std::uint64_t stereo(int frame);   // ZNCC stereo at frame's corners
  std::uint64_t descriptors();       // oriented descriptors at the 300 corners of frame 0
  std::uint64_t downsample();        // a 1280 x 1024 frame to 320 x 256 (the Mars camera's factor 4)
  std::uint64_t match_fb();          // landmarks of frame 0 against frame 1, binary scores
  std::uint64_t match_fc();          // continuous scores, full search
  std::uint64_t match_fast();        // continuous scores, fast batches
  std::uint64_t motion_6d();         // Arun + IRLS on the fc matches
  std::uint64_t motion_3d();         // 3D-VME (rotation from attitude) + IRLS on the same matches
  // Step k (0 or 1): frame k is processed first as the reference (outside the counted region: call
  // vo_reference(k) before), then vo_step(k) processes frame k + 1.
  void vo_reference(int step);
  std::uint64_t vo_step(int step);

 private:
  struct Impl;
  std::unique_ptr<Impl> d_;
};

// XTF decoding (the byte-order-sensitive parser), scanline correction (bottom detection on), one tile build (the daemon's 704 x 704 raster) and the
// tile's features, on simulated side-scan pings of the default route survey.
class CannedSonar {
 public:
  static constexpr int kPings = 8;
  CannedSonar();
  ~CannedSonar();
  Status init();
  std::uint64_t xtf_decode(int ping);  // one XTF sonar packet (2 x 512 samples) decoded
  std::uint64_t scanline(int ping);
  void tile_prepare();            // pushes all but the last scanline of a tile (not counted)
  std::uint64_t tile_build();     // the last push: builds the raster
  void features_prepare();        // builds the tile first when sonar_tile has not run (not counted)
  std::uint64_t tile_features();  // keypoints of the built tile

 private:
  struct Impl;
  std::unique_ptr<Impl> d_;
};

// Tile registration, a route-filter update on a 10,000-node route at the searching budget (the
// daemon's localiser configuration, 16 registrations; and with 4 experiences on every node, up to 32;
// the nodes an update loads are decoded from route records encoded in init(), as a flight load from
// the route file) and a downward-camera tile projection.
class CannedRoute {
 public:
  static constexpr int kUpdates = 3;
  static constexpr std::uint32_t kRouteNodes = 10000;
  CannedRoute();
  ~CannedRoute();
  Status init();
  std::uint64_t registration(int pair);  // pair 0..2
  void route_restart();                   // localiser back to a uniform belief (not counted)
  std::uint64_t route_update(int k);      // one step with sensed tile k, searching
  // The same with experiences (issue 29): kExperiencesPerNode on every node (qnavd's default
  // route.max_experiences, pipeline::enable_experiences: up to 16 extra registrations per update).
  static constexpr std::uint16_t kExperiencesPerNode = 4;
  void route_restart_exp();               // (not counted)
  std::uint64_t route_update_exp(int k);
  void predict_reset();                   // a 100,000-node belief back to uniform (not counted)
  std::uint64_t predict_100k();           // one belief prediction over 100,000 nodes
  std::uint64_t camera_tile(int k);       // k = 0, 1: two headings

 private:
  struct Impl;
  std::unique_ptr<Impl> d_;
};

// One downward frame through the mapper qnavd's map mode runs (pipeline::TopoMapper::step: homography
// chain + place signature + topological map; no map file save), on the synthetic seabed loop `qnav map
// eval` flies (drivers/downward_sim: 320 x 240, f 300 px, 2 m up, 90 frames a lap, metric, node spacing
// 0.2 m, 1024 nodes: qnavd's example map configuration). The frames are rendered at init() (the 6 MB
// seabed raster is freed after); the mapper takes frame 0 as its reference outside the counted region.
// (canned_map.cpp: not in the freestanding LEON3 image's workload.)
class CannedMap {
 public:
  static constexpr int kSteps = 3;  // frames 1..3 registered against the keyframe (frame 0)
  CannedMap();
  ~CannedMap();
  Status init();
  void restart();                  // mapper re-initialised, frame 0 as the reference (not counted)
  std::uint64_t step(int k);       // frame k + 1 (k = 0 .. kSteps - 1), in order after restart()

 private:
  struct Impl;
  std::unique_ptr<Impl> d_;
};

// The MAVLink codec (drivers/mavlink) per message, as qnavd's MAVLink endpoint uses it: encode one
// message to a complete MAVLink 2 frame (FrameEncoder + the typed payload), parse one frame from a byte
// stream (Parser::feed + the typed decode), sign a frame (SHA-256) and parse a signed one (verification
// and replay check). Each call does one message; result() hashes the last call's output afterwards
// (outside the counted region: hashing a frame costs more than encoding it).
// (canned_mavlink.cpp: not in the freestanding LEON3 image's workload.)
class CannedMavlink {
 public:
  static constexpr int kCalls = 8;  // messages per stage, each with other field values
  enum Kind : int { kOdometry, kDelta, kDistance, kHeartbeat, kNamed, kCommand, kSignedOdometry, kSign, kKinds };
  CannedMavlink();
  ~CannedMavlink();
  Status init();
  std::uint64_t encode(int kind, int k);  // kOdometry .. kNamed; returns the frame length (0: failed)
  std::uint64_t parse(int kind, int k);   // kOdometry .. kSignedOdometry; 1 when the frame decoded
  std::uint64_t sign(int k);              // signs an ODOMETRY frame
  std::uint64_t result(bool parsed) const;  // hash of the last call's frame (encode, sign) or fields (parse)

 private:
  struct Impl;
  std::unique_ptr<Impl> d_;
};

}  // namespace qnav::timing
