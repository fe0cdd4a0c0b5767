#include <benchmark/benchmark.h>

#include <cstring>

#include "drivers/camera/stereo_pairer.hpp"
#include "drivers/dronecan/ahrs_receiver.hpp"
#include "drivers/dvl/pd6_parser.hpp"
#include "drivers/dvl/wl_parser.hpp"
#include "drivers/qnavcan/receiver.hpp"
#include "hal/core/candump.hpp"

using namespace qnav;

static void BM_CandumpParseLine(benchmark::State& st) {
  const char* line = "(1436509052.249713) vcan0 1F334455#1122334455667788";
  const std::size_t n = std::strlen(line);
  hal::CanLogRecord r;
  for (auto _ : st) {
    benchmark::DoNotOptimize(hal::parse_can_log_line(line, n, r));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_CandumpParseLine);

static void BM_QnavCanReceiveAttitude(benchmark::State& st) {
  drivers::qnavcan::QnavCanReceiver rx;
  hal::CanRxFrame f;
  drivers::qnavcan::AttitudeIn a{-0.1, 0.05, 3.0, 0, true};
  std::uint8_t c = 0;
  std::int64_t t = 0;
  for (auto _ : st) {
    a.counter = c++;
    drivers::qnavcan::encode(a, f.frame).ignore();
    f.stamp.sample_ns = (t += 20000000);
    benchmark::DoNotOptimize(rx.on_frame(f));
  }
  st.SetLabel("encode + decode + checks, one 8-byte frame");
}
BENCHMARK(BM_QnavCanReceiveAttitude);

static void BM_DroneCanSolutionTransfer(benchmark::State& st) {
  drivers::dronecan::AhrsSolution s;
  s.orientation_xyzw[3] = 1;
  std::uint8_t payload[drivers::dronecan::kSolutionMaxBytes];
  const std::size_t n = drivers::dronecan::encode_solution(s, true, payload, sizeof payload);
  drivers::dronecan::DroneCanAhrsReceiver rx;
  hal::CanFrame frames[16];
  std::uint8_t tid = 0;
  std::uint64_t ts = 1;
  std::int64_t t = 0;
  for (auto _ : st) {
    st.PauseTiming();
    s.timestamp_us = ts++;
    drivers::dronecan::encode_solution(s, true, payload, sizeof payload);
    const std::size_t k = drivers::dronecan::split_transfer(drivers::dronecan::kSolutionSignature,
                                                            drivers::dronecan::make_message_id(16, 1000, 42), tid++, payload, n, frames, 16);
    st.ResumeTiming();
    for (std::size_t i = 0; i < k; ++i) {
      hal::CanRxFrame f;
      f.frame = frames[i];
      f.stamp.sample_ns = (t += 100000);
      benchmark::DoNotOptimize(rx.on_frame(f));
    }
  }
  st.SetLabel("5 frames: reassembly + CRC + DSDL decode + checks");
}
BENCHMARK(BM_DroneCanSolutionTransfer);

static void BM_WaterLinkedWrz(benchmark::State& st) {
  drivers::dvl::WlParser p;
  char line[200];
  drivers::dvl::WlMessage m;
  long long tov = 1;
  for (auto _ : st) {
    st.PauseTiming();
    char body[180];
    std::snprintf(body, sizeof body, "wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,%lld,%lld,123.00,1", tov, tov + 7);
    ++tov;
    const std::size_t n = drivers::dvl::wl_with_checksum(body, line, sizeof line);
    st.ResumeTiming();
    benchmark::DoNotOptimize(p.parse_line(line, n, 0, m));
  }
  st.SetLabel("one wrz sentence (CRC-8 + 19 numbers)");
}
BENCHMARK(BM_WaterLinkedWrz);

static void BM_Pd6Ensemble(benchmark::State& st) {
  static const char* kLines[] = {":SA, +0.00, +0.00,  0.00", nullptr, ":WI,    +0,    +0,    +0,    +0,V",
                                 ":WS,    +0,    +0,    +0,V", ":WE,    +0,    +0,    +0,V",
                                 ":WD,       +0.00,       +0.00,       +0.00,   0.00,  0.00",
                                 ":BI,  +123,  -420, +2000,    +0,A", ":BS,  -420,  +123, +2000,A", ":BE,    +0,    +0,    +0,V",
                                 ":BD,       +0.00,       +0.00,       +0.00,   5.32,  0.00"};
  drivers::dvl::Pd6Parser p;
  drivers::dvl::Pd6Ensemble e;
  int cs = 0;
  char ts[64];
  for (auto _ : st) {
    st.PauseTiming();
    std::snprintf(ts, sizeof ts, ":TS,220208%02d%02d%02d%02d, 0.0, +0.0,   0.0,1475.0,  0", (cs / 360000) % 24, (cs / 6000) % 60,
                  (cs / 100) % 60, cs % 100);
    ++cs;
    st.ResumeTiming();
    for (int i = 0; i < 10; ++i) {
      const char* l = i == 1 ? ts : kLines[i];
      benchmark::DoNotOptimize(p.parse_line(l, std::strlen(l), 0, e));
    }
  }
  st.SetLabel("10 lines = one ensemble");
}
BENCHMARK(BM_Pd6Ensemble);

static void BM_StereoPairerPush(benchmark::State& st) {
  drivers::camera::StereoPairer p(2000000);
  drivers::camera::PairRef out;
  std::uint8_t dropped[drivers::camera::StereoPairer::kDepth + 1];
  std::size_t nd = 0;
  std::int64_t t = 0;
  std::uint32_t seq = 0;
  for (auto _ : st) {
    t += 50000000;
    drivers::camera::FrameRef l, r;
    l.sequence = r.sequence = seq++;
    l.stamp.sample_ns = t;
    r.stamp.sample_ns = t + 300000;
    l.slot = r.slot = static_cast<std::uint8_t>(seq % 4);
    p.push(drivers::camera::Side::kLeft, l, out, dropped, nd);
    benchmark::DoNotOptimize(p.push(drivers::camera::Side::kRight, r, out, dropped, nd));
  }
  st.SetLabel("left + right push = one pair");
}
BENCHMARK(BM_StereoPairerPush);

BENCHMARK_MAIN();
