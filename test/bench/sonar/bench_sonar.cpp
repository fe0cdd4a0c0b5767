// Side-scan chain throughput, single thread. The goal (issue 5): >= 20,000 pings/s for 2 x 1024
// samples through decode + correction + tile placement (a 10 Hz sonar needs 10).
// items_per_second = pings per second. Inputs are simulated pings (seeded), written to XTF once.
#include <benchmark/benchmark.h>

#include <vector>

#include "drivers/sidescan/sim_seabed.hpp"
#include "drivers/sidescan/sim_sidescan.hpp"
#include "drivers/sidescan/sim_trajectory.hpp"
#include "drivers/sidescan/xtf_parser.hpp"
#include "drivers/sidescan/xtf_writer.hpp"
#include "nav/sonar/scanline_corrector.hpp"
#include "nav/sonar/tile_builder.hpp"

namespace {

using namespace qnav;
using namespace qnav::sidescan;

constexpr int kSamples = 1024;
constexpr int kPings = 64;

// kPings simulated pings (2 x 1024 samples, 40 m range, 8 m altitude) as XTF packets + poses.
struct Data {
  XtfFileHeader header;
  std::vector<std::vector<std::uint8_t>> packets;
  std::vector<Pose2> poses;
  Data() {
    std::vector<std::uint8_t> h(kXtfFileHeaderBytes);
    (void)encode_xtf_file_header(Span<std::uint8_t>(h.data(), h.size()), 0, "BENCH");
    header = parse_xtf_file_header(Span<const std::uint8_t>(h.data(), h.size())).value();
    Seabed bed;
    (void)bed.init(SeabedConfig{});
    SideScanSimConfig sc;
    sc.samples_per_side = kSamples;
    sc.slant_range_m = 40.0f;
    SideScanSimulator sim;
    (void)sim.init(sc, &bed);
    std::vector<float> port(kSamples), stbd(kSamples);
    for (int k = 0; k < kPings; ++k) {
      const Pose2 pose{k * 0.15, 0.0, 0.0};
      (void)sim.ping(pose, 8.0f, static_cast<std::uint32_t>(k), Span<float>(port.data(), kSamples), Span<float>(stbd.data(), kSamples));
      XtfWritePing w;
      w.ping_number = static_cast<std::uint32_t>(k);
      w.slant_range_m = 40.0f;
      w.altitude_m = 8.0f;
      w.port = Span<const float>(port.data(), kSamples);
      w.stbd = Span<const float>(stbd.data(), kSamples);
      w.sample_scale = 4.0f;
      std::vector<std::uint8_t> p(xtf_ping_bytes(kSamples));
      (void)encode_xtf_ping(Span<std::uint8_t>(p.data(), p.size()), w);
      packets.push_back(std::move(p));
      poses.push_back(pose);
    }
  }
};
const Data& data() {
  static const Data d;
  return d;
}

sonar::ScanlineCorrectorConfig corrector_config() {
  sonar::ScanlineCorrectorConfig c;
  c.max_samples_per_side = kSamples;
  c.ground_bins_per_side = 400;  // 0.1 m bins to 40 m
  c.ground_bin_m = 0.1f;
  return c;
}
sonar::TileBuilderConfig tile_config() {
  sonar::TileBuilderConfig t;
  t.resolution_m = 0.1;
  t.tile_width_px = 1024;
  t.tile_height_px = 1024;
  t.scanlines_per_tile = 500;
  t.scanline_stride = 500;
  t.max_bins_per_side = 400;
  return t;
}

void BM_XtfDecodePing(benchmark::State& st) {
  const Data& d = data();
  std::vector<float> port(kSamples), stbd(kSamples);
  XtfPing p;
  std::size_t k = 0;
  for (auto _ : st) {
    const auto& pk = d.packets[k++ % d.packets.size()];
    benchmark::DoNotOptimize(parse_xtf_sonar_ping(Span<const std::uint8_t>(pk.data(), pk.size()), d.header, p,
                                                  Span<float>(port.data(), kSamples), Span<float>(stbd.data(), kSamples)));
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_XtfDecodePing);

void BM_CorrectPing(benchmark::State& st) {
  const Data& d = data();
  const bool detect = st.range(0) != 0;
  ArenaStorage arena(sonar::ScanlineCorrector::arena_bytes(corrector_config()));
  sonar::ScanlineCorrector corr;
  (void)corr.init(corrector_config(), arena);
  std::vector<std::vector<float>> port(kPings, std::vector<float>(kSamples)), stbd(kPings, std::vector<float>(kSamples));
  XtfPing p;
  for (int k = 0; k < kPings; ++k)
    (void)parse_xtf_sonar_ping(Span<const std::uint8_t>(d.packets[static_cast<std::size_t>(k)].data(), d.packets[static_cast<std::size_t>(k)].size()),
                               d.header, p, Span<float>(port[static_cast<std::size_t>(k)].data(), kSamples),
                               Span<float>(stbd[static_cast<std::size_t>(k)].data(), kSamples));
  sonar::CorrectedScanline line;
  std::size_t k = 0;
  for (auto _ : st) {
    const std::size_t i = k++ % kPings;
    sonar::SonarPing ping;
    ping.port = Span<const float>(port[i].data(), kSamples);
    ping.stbd = Span<const float>(stbd[i].data(), kSamples);
    ping.slant_range_m = 40.0f;
    ping.altitude_m = detect ? -1.0f : 8.0f;
    benchmark::DoNotOptimize(corr.correct(ping, line));
  }
  st.SetItemsProcessed(st.iterations());
  st.SetLabel(detect ? "bottom detection" : "altimeter");
}
BENCHMARK(BM_CorrectPing)->Arg(0)->Arg(1);

// The whole per-ping chain: XTF decode + correction (bottom detection) + tile push, with the tile
// build every 500 pings amortised into the rate.
void BM_PipelinePerPing(benchmark::State& st) {
  const Data& d = data();
  ArenaStorage arena(sonar::ScanlineCorrector::arena_bytes(corrector_config()) + sonar::TileBuilder::arena_bytes(tile_config()));
  sonar::ScanlineCorrector corr;
  sonar::TileBuilder tb;
  (void)corr.init(corrector_config(), arena);
  (void)tb.init(tile_config(), arena);
  std::vector<float> port(kSamples), stbd(kSamples);
  XtfPing p;
  sonar::CorrectedScanline line;
  std::uint64_t k = 0;
  for (auto _ : st) {
    const auto& pk = d.packets[k % kPings];
    (void)parse_xtf_sonar_ping(Span<const std::uint8_t>(pk.data(), pk.size()), d.header, p, Span<float>(port.data(), kSamples),
                               Span<float>(stbd.data(), kSamples));
    sonar::SonarPing ping;
    ping.port = Span<const float>(port.data(), kSamples);
    ping.stbd = Span<const float>(stbd.data(), kSamples);
    ping.slant_range_m = p.slant_range_m;
    ping.altitude_m = -1.0f;
    (void)corr.correct(ping, line);
    const Pose2 pose{static_cast<double>(k) * 0.15, 0.0, 0.0};
    benchmark::DoNotOptimize(tb.push(line, pose));
    ++k;
  }
  st.SetItemsProcessed(st.iterations());
  st.counters["tiles"] = static_cast<double>(tb.tiles_built());
}
BENCHMARK(BM_PipelinePerPing);

void BM_TileBuild500(benchmark::State& st) {
  const Data& d = data();
  sonar::TileBuilderConfig tc = tile_config();
  ArenaStorage arena(sonar::ScanlineCorrector::arena_bytes(corrector_config()) + sonar::TileBuilder::arena_bytes(tc));
  sonar::ScanlineCorrector corr;
  sonar::TileBuilder tb;
  (void)corr.init(corrector_config(), arena);
  (void)tb.init(tc, arena);
  std::vector<float> port(kSamples), stbd(kSamples);
  XtfPing p;
  sonar::CorrectedScanline line;
  (void)parse_xtf_sonar_ping(Span<const std::uint8_t>(d.packets[0].data(), d.packets[0].size()), d.header, p,
                             Span<float>(port.data(), kSamples), Span<float>(stbd.data(), kSamples));
  sonar::SonarPing ping;
  ping.port = Span<const float>(port.data(), kSamples);
  ping.stbd = Span<const float>(stbd.data(), kSamples);
  ping.slant_range_m = 40.0f;
  ping.altitude_m = 8.0f;
  (void)corr.correct(ping, line);
  for (int k = 0; k < 499; ++k) (void)tb.push(line, Pose2{k * 0.15, 0.0, 0.0});
  for (auto _ : st) {
    // flush() rebuilds the tile from the 499 buffered scanlines (the build cost alone).
    st.PauseTiming();
    tb.reset();
    for (int k = 0; k < 499; ++k) (void)tb.push(line, Pose2{k * 0.15, 0.0, 0.0});
    st.ResumeTiming();
    benchmark::DoNotOptimize(tb.flush());
  }
  st.SetItemsProcessed(st.iterations());
  st.SetLabel("tiles/s, 499 scanlines x 2 x 400 bins into 1024^2 px");
}
BENCHMARK(BM_TileBuild500)->Unit(benchmark::kMillisecond);

void BM_SimulatorPing(benchmark::State& st) {
  Seabed bed;
  (void)bed.init(SeabedConfig{});
  SideScanSimConfig sc;
  sc.samples_per_side = static_cast<int>(st.range(0));
  sc.slant_range_m = 40.0f;
  SideScanSimulator sim;
  (void)sim.init(sc, &bed);
  std::vector<float> port(static_cast<std::size_t>(sc.samples_per_side)), stbd(port.size());
  std::uint32_t k = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(sim.ping(Pose2{k * 0.15, 0.0, 0.3}, 8.0f, k, Span<float>(port.data(), port.size()),
                                      Span<float>(stbd.data(), stbd.size())));
    ++k;
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_SimulatorPing)->Arg(512)->Arg(1024);

}  // namespace

BENCHMARK_MAIN();
