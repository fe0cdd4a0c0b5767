// timing_stages: every stage of the static pipeline on canned, deterministic inputs (canned.hpp), each
// call bracketed by a region marker (region.hpp), for the per-target instruction budgets. Run under
// the counter:
//   toolchain/count-instructions aarch64 build/aarch64/test/timing/timing_stages
// The program prints its region table ("stage ID NAME CALLS") and a hash of each stage's results
// ("hash NAME HEX"); the counter prints "region ID calls C total T min A max B" per region at exit.
// test/timing/check-budgets.py joins both and compares each stage's worst call with its budget.
// Optional argument: a stage name, to run that stage alone (for profiling one stage).
#include <cinttypes>
#include <cstdio>
#include <cstring>

#include "test/timing/canned.hpp"
#include "test/timing/region.hpp"

namespace {

using namespace qnav::timing;

struct Canned {
  CannedVo vo;
  CannedSonar sonar;
  CannedRoute route;
  CannedMap map;
  CannedMavlink mav;
};

struct StageDef {
  const char* name;
  int calls;
  void (*prepare)(Canned&, int call);  // not counted
  std::uint64_t (*run)(Canned&, int call);
  // When set, the stage's result hash is taken after the region (run returns only whether it worked):
  // for stages so short that hashing their output would cost more than the stage.
  std::uint64_t (*result)(Canned&) = nullptr;
};

std::uint64_t mav_frame(Canned& c) { return c.mav.result(false); }
std::uint64_t mav_fields(Canned& c) { return c.mav.result(true); }
constexpr int kMav = CannedMavlink::kCalls;
using K = CannedMavlink::Kind;

void nothing(Canned&, int) {}

// Region ids are the indices in this table; "marker" (an empty region) measures the markers' own cost.
const StageDef kStages[] = {
    {"marker", 4, nothing, [](Canned&, int) -> std::uint64_t { return 0; }},
    {"harris", 3, nothing, [](Canned& c, int k) { return c.vo.harris(k); }},
    {"remap", 2, nothing, [](Canned& c, int k) { return c.vo.remap(k); }},
    {"stereo", 3, nothing, [](Canned& c, int k) { return c.vo.stereo(k); }},
    {"match_fb", 1, nothing, [](Canned& c, int) { return c.vo.match_fb(); }},
    {"match_fc", 1, nothing, [](Canned& c, int) { return c.vo.match_fc(); }},
    {"match_fast", 1, nothing, [](Canned& c, int) { return c.vo.match_fast(); }},
    {"motion_6d", 1, nothing, [](Canned& c, int) { return c.vo.motion_6d(); }},
    {"motion_3d", 1, nothing, [](Canned& c, int) { return c.vo.motion_3d(); }},
    {"vo_step", 2, [](Canned& c, int k) { c.vo.vo_reference(k); }, [](Canned& c, int k) { return c.vo.vo_step(k); }},
    {"scanline", CannedSonar::kPings, nothing, [](Canned& c, int k) { return c.sonar.scanline(k); }},
    {"sonar_tile", 1, [](Canned& c, int) { c.sonar.tile_prepare(); }, [](Canned& c, int) { return c.sonar.tile_build(); }},
    {"tile_features", 1, [](Canned& c, int) { c.sonar.features_prepare(); }, [](Canned& c, int) { return c.sonar.tile_features(); }},
    {"registration", 3, nothing, [](Canned& c, int k) { return c.route.registration(k); }},
    {"route_update", CannedRoute::kUpdates, [](Canned& c, int) { c.route.route_restart(); },
     [](Canned& c, int k) { return c.route.route_update(k); }},
    {"camera_tile", 2, nothing, [](Canned& c, int k) { return c.route.camera_tile(k); }},
    {"descriptor", 1, nothing, [](Canned& c, int) { return c.vo.descriptors(); }},
    {"downsample", 1, nothing, [](Canned& c, int) { return c.vo.downsample(); }},
    {"xtf_decode", CannedSonar::kPings, nothing, [](Canned& c, int k) { return c.sonar.xtf_decode(k); }},
    {"route_predict_100k", 1, [](Canned& c, int) { c.route.predict_reset(); }, [](Canned& c, int) { return c.route.predict_100k(); }},
    {"map", CannedMap::kSteps, [](Canned& c, int k) { if (k == 0) c.map.restart(); }, [](Canned& c, int k) { return c.map.step(k); }},
    {"route_update_exp", CannedRoute::kUpdates, [](Canned& c, int) { c.route.route_restart_exp(); },
     [](Canned& c, int k) { return c.route.route_update_exp(k); }},
    {"mav_enc_odometry", kMav, nothing, [](Canned& c, int k) { return c.mav.encode(K::kOdometry, k); }, mav_frame},
    {"mav_parse_odometry", kMav, nothing, [](Canned& c, int k) { return c.mav.parse(K::kOdometry, k); }, mav_fields},
    {"mav_enc_vpd", kMav, nothing, [](Canned& c, int k) { return c.mav.encode(K::kDelta, k); }, mav_frame},
    {"mav_parse_vpd", kMav, nothing, [](Canned& c, int k) { return c.mav.parse(K::kDelta, k); }, mav_fields},
    {"mav_enc_distance", kMav, nothing, [](Canned& c, int k) { return c.mav.encode(K::kDistance, k); }, mav_frame},
    {"mav_parse_distance", kMav, nothing, [](Canned& c, int k) { return c.mav.parse(K::kDistance, k); }, mav_fields},
    {"mav_enc_heartbeat", kMav, nothing, [](Canned& c, int k) { return c.mav.encode(K::kHeartbeat, k); }, mav_frame},
    {"mav_parse_heartbeat", kMav, nothing, [](Canned& c, int k) { return c.mav.parse(K::kHeartbeat, k); }, mav_fields},
    {"mav_enc_named_float", kMav, nothing, [](Canned& c, int k) { return c.mav.encode(K::kNamed, k); }, mav_frame},
    {"mav_parse_named_float", kMav, nothing, [](Canned& c, int k) { return c.mav.parse(K::kNamed, k); }, mav_fields},
    {"mav_parse_command_long", kMav, nothing, [](Canned& c, int k) { return c.mav.parse(K::kCommand, k); }, mav_fields},
    {"mav_sign_odometry", kMav, nothing, [](Canned& c, int k) { return c.mav.sign(k); }, mav_frame},
    {"mav_parse_signed_odometry", kMav, nothing, [](Canned& c, int k) { return c.mav.parse(K::kSignedOdometry, k); }, mav_fields},
};

}  // namespace

int main(int argc, char** argv) {
  const char* only = argc > 1 ? argv[1] : nullptr;
  bool known = only == nullptr;
  for (const StageDef& s : kStages) known = known || std::strcmp(s.name, only) == 0;
  if (!known) {
    std::fprintf(stderr, "timing_stages: unknown stage '%s'; stages:", only);
    for (const StageDef& s : kStages) std::fprintf(stderr, " %s", s.name);
    std::fprintf(stderr, "\n");
    return 2;
  }
  static Canned canned;
  for (const qnav::Status& st : {canned.vo.init(), canned.sonar.init(), canned.route.init(), canned.map.init(), canned.mav.init()}) {
    if (!st.is_ok()) {
      std::fprintf(stderr, "timing_stages: canned inputs failed: %s\n", st.message());
      return 1;
    }
  }
  int failed = 0;
  for (int id = 0; id < static_cast<int>(sizeof kStages / sizeof kStages[0]); ++id) {
    const StageDef& s = kStages[id];
    if (only != nullptr && std::strcmp(s.name, only) != 0 && id != 0) continue;
    Hash all;
    for (int k = 0; k < s.calls; ++k) {
      s.prepare(canned, k);
      region_begin(id);
      std::uint64_t h = s.run(canned, k);
      region_end(id);
      if (s.result != nullptr && h != 0) h = s.result(canned);
      // A stage that failed on its canned input returns 0: its count would be meaningless.
      if (h == 0 && id != 0) {
        std::fprintf(stderr, "timing_stages: stage %s call %d failed on its canned input\n", s.name, k);
        ++failed;
      }
      all.add(h);
    }
    std::printf("stage %d %s %d\n", id, s.name, s.calls);
    std::printf("hash %s %016" PRIx64 "\n", s.name, all.value());
  }
  std::fflush(stdout);
  return failed == 0 ? 0 : 1;
}
