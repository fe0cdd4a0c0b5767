// Shared helpers of the MAVLink codec tests: a seeded byte generator, frames of every known message
// from random payloads, and a parser sink that records what it delivers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "drivers/mavlink/frame.hpp"
#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"

namespace qnav::drivers::mavlink::test {

struct Lcg {
  std::uint32_t s;
  explicit Lcg(std::uint32_t seed) : s(seed) {}
  std::uint32_t next() {
    s = s * 1664525u + 1013904223u;
    return s;
  }
  std::uint8_t byte() { return static_cast<std::uint8_t>(next() >> 24); }
  std::uint32_t below(std::uint32_t n) { return static_cast<std::uint32_t>((static_cast<std::uint64_t>(next()) * n) >> 32); }
};

// Strings end at their first NUL on the wire too: zero everything after it so that a random payload
// survives decode -> encode byte for byte.
inline void normalise_strings(std::uint32_t msgid, std::uint8_t* p) {
  std::size_t from = 0, n = 0;
  if (msgid == NamedValueFloat::kId) { from = 8; n = 10; }
  if (msgid == StatusText::kId) { from = 1; n = 50; }
  bool ended = false;
  for (std::size_t i = from; i < from + n; ++i) {
    if (p[i] == 0) ended = true;
    if (ended) p[i] = 0;
  }
}

// decode_payload then encode_payload of the typed message with id `msgid` (false: not a typed id).
inline bool typed_round_trip(std::uint32_t msgid, const std::uint8_t* in, std::uint8_t* out) {
  switch (msgid) {
#define QNAV_CASE(T) case T::kId: { T m; decode_payload(in, m); encode_payload(m, out); return true; }
    QNAV_CASE(Heartbeat) QNAV_CASE(SystemTime) QNAV_CASE(Attitude) QNAV_CASE(LocalPositionNed)
    QNAV_CASE(SetGpsGlobalOrigin) QNAV_CASE(GpsGlobalOrigin) QNAV_CASE(CommandLong) QNAV_CASE(CommandAck) QNAV_CASE(SetPositionTargetLocalNed)
    QNAV_CASE(VisionPositionEstimate) QNAV_CASE(VisionSpeedEstimate) QNAV_CASE(DistanceSensor)
    QNAV_CASE(EkfStatusReport) QNAV_CASE(NamedValueFloat) QNAV_CASE(StatusText) QNAV_CASE(Odometry)
    QNAV_CASE(VisionPositionDelta)
#undef QNAV_CASE
    default: return false;
  }
}

struct Sink {
  std::vector<Frame> frames;
  void operator()(const Frame& f) { frames.push_back(f); }
};

inline void feed_all(Parser& p, const std::vector<std::uint8_t>& bytes, Sink& sink) {
  p.feed(Span<const std::uint8_t>(bytes.data(), bytes.size()), [&](const Frame& f) { sink(f); });
}

}  // namespace qnav::drivers::mavlink::test
