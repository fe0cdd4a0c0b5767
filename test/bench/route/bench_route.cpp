// bench_route: see CMakeLists.txt. Numbers are CPU time per iteration (google benchmark).
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include "nav/core/arena.hpp"
#include "nav/route/registration.hpp"
#include "nav/route/route_filter.hpp"
#include "nav/route/route_localiser.hpp"
#include "synthetic_route.hpp"

namespace {

using namespace qnav;
using namespace qnav::route;

void BM_RouteFilterPredict(benchmark::State& state) {
  RouteFilterConfig c;
  c.max_nodes = static_cast<std::size_t>(state.range(0));
  ArenaStorage arena(RouteFilter::arena_bytes(c));
  RouteFilter f;
  if (!f.init(c, arena) || !f.reset(static_cast<std::uint32_t>(c.max_nodes), 60.0)) state.SkipWithError("init");
  for (auto _ : state) {
    f.predict(60.0).ignore();
    benchmark::DoNotOptimize(f.argmax());
  }
}
BENCHMARK(BM_RouteFilterPredict)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

constexpr double kSpacing = 60.0;

// The configuration `qnav route eval` uses: 128 keypoints per tile and node, 3 candidates each.
void BM_Registration128(benchmark::State& state) {
  testing::SyntheticWorld world(2000.0, 200.0, 0.008, 3);
  RouteNode a = world.observe(Pose2{300.0, 12.0, 0.02}, 45.0, 49.0, 0.3, 0.8, 128, 1, 20);
  RouteNode b = world.observe(Pose2{310.0, 0.0, 0.0}, 45.0, 49.0, 0.3, 0.8, 128, 2, 20);
  RegistrationConfig c;
  c.fc.max_points = 128;
  c.fc.sigma_dir_rad = 0.02;
  c.fc.max_candidates_per_point = 3;
  c.robust.min_inliers = 5;
  ArenaStorage arena(Registrar::arena_bytes(c));
  Registrar r;
  if (!r.init(c, arena)) state.SkipWithError("init");
  RegistrationResult out;
  for (auto _ : state) {
    r.register_tile(a, b, out).ignore();
    benchmark::DoNotOptimize(out.inliers);
  }
  state.counters["inliers"] = out.inliers;
}
BENCHMARK(BM_Registration128)->Unit(benchmark::kMillisecond);

void BM_LocaliserUpdate10000(benchmark::State& state) {
  testing::SyntheticWorld world(1900.0, 200.0, 0.008, 3);
  const std::uint32_t n = 10000;
  testing::RepeatingRouteSource src(&world, n, kSpacing);
  std::vector<NodeMeta> meta(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    meta[i].index = i;
    meta[i].pose = Pose2{30.0 + kSpacing * i, 0.0, 0.0};
    meta[i].along_m = kSpacing * i;
  }
  LocaliserConfig c;
  c.filter.max_nodes = n;
  c.filter.belief_registrations = 4;
  c.filter.wide_search_registrations = 6;
  c.filter.searching_registrations = 16;
  c.registration.fc.max_points = 128;
  c.registration.fc.sigma_dir_rad = 0.02;
  c.registration.fc.max_candidates_per_point = 3;
  c.registration.robust.min_inliers = 5;
  ArenaStorage arena(RouteLocaliser::arena_bytes(c));
  auto loc = std::make_unique<RouteLocaliser>();
  RouteParams p;
  p.sensor = SensorKind::kSideScan;
  p.node_spacing_m = static_cast<float>(kSpacing);
  if (!loc->init(c, arena) || !loc->start(p, Span<const NodeMeta>(meta.data(), n), src)) state.SkipWithError("init");
  std::vector<RouteNode> tiles;
  for (int k = 0; k < 16; ++k)
    tiles.push_back(world.observe(Pose2{30.0 + kSpacing * (5 + k) + 10.0, 15.0, 0.0}, 45.0, 49.0, 0.3, 0.8, 128, 50 + static_cast<std::uint64_t>(k), 20));
  std::size_t k = 0;
  LocaliserStep st;
  for (auto _ : state) {
    loc->step(tiles[k % tiles.size()], kSpacing, st).ignore();
    ++k;
    benchmark::DoNotOptimize(st.estimate);
  }
  state.counters["registrations"] = st.registrations;
}
BENCHMARK(BM_LocaliserUpdate10000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
