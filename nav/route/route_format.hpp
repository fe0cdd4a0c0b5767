// The route file format (version 1): byte-level encode and decode with CRC-32. No I/O here: the
// fsync'ing writer and the bounded reader live in firmware/tools/route_file.{hpp,cpp}.
//
// Layout (all multi-byte fields little-endian, floats IEEE-754; decoded with nav/core/byte_order):
//   header, kHeaderBytes = 64:
//     0  char[8]  magic "QNAVRTE\0"     8  u16 version (1)       10 u16 header_bytes (64)
//     12 u8 sensor_kind  13 u8 reserved 14 u16 max_keypoints     16 u16 descriptor_bytes (64)
//     18 u16 harris_window_px           20 u16 keypoint_min_distance_px   22 u16 reserved
//     24 f32 depth_m  28 f32 node_spacing_m  32 f32 tile_length_m  36 f32 tile_width_m
//     40 f32 pixel_m  44..59 reserved (zero)                       60 u32 crc32 of bytes 0..59
//   then one fixed-size record per node, record_bytes(max_keypoints):
//     0 u32 magic "QRND"  4 u32 node_index  8 f64 x_m  16 f64 y_m  24 f32 heading_rad
//     28 f64 along_m  36 u16 keypoint_count  38 u16 reserved  40 u64 stamp_ns
//     48 max_keypoints x { f32 x_m, f32 y_m, f32 score, i8[64] descriptor } (unused slots zero)
//     last 4 bytes: u32 crc32 of everything before it in the record.
// Fixed-size records make node i addressable at header + i * record_bytes (bounded reads of any
// node without an index) and make a torn tail visible as a file length that is not a whole number
// of records. Every decode checks magic, CRC, counts and finiteness: a damaged record is reported
// (kCorrupt), never half-used. Cost O(record bytes), no heap.
#pragma once

#include <cstddef>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "nav/core/byte_order.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/crc.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::route {

constexpr std::uint16_t kRouteFormatVersion = 1;
constexpr std::size_t kHeaderBytes = 64;
constexpr std::size_t kRecordFixedBytes = 48;
constexpr std::size_t kKeypointBytes = 12 + kDescriptorBytes;

enum class RouteFormatCounter : std::uint8_t {
  kBadHeaderMagic, kBadHeaderCrc, kUnsupportedVersion, kBadParams,
  kBadRecordMagic, kBadRecordCrc, kBadRecordIndex, kBadRecordField, kShortBuffer, kCount
};
inline constexpr const char* kRouteFormatCounterNames[] = {
    "bad_header_magic", "bad_header_crc", "unsupported_version", "bad_params",
    "bad_record_magic", "bad_record_crc", "bad_record_index", "bad_record_field", "short_buffer"};
using RouteFormatCounters = CounterSet<RouteFormatCounter>;

// Bytes of one node record for a route with max_keypoints slots.
constexpr std::size_t record_bytes(std::size_t max_keypoints) noexcept {
  return kRecordFixedBytes + max_keypoints * kKeypointBytes + 4;
}

// Checks parameters a writer may put in a header (sizes within bounds, finite positive lengths).
Status validate_params(const RouteParams& p) noexcept;

// out.size() >= kHeaderBytes.
Status encode_header(const RouteParams& p, Span<std::uint8_t> out) noexcept;
Result<RouteParams> decode_header(Span<const std::uint8_t> in, RouteFormatCounters* counters) noexcept;

// out.size() >= record_bytes(p.max_keypoints); node.keypoints.size() <= p.max_keypoints.
Status encode_node(const RouteParams& p, const RouteNode& node, Span<std::uint8_t> out) noexcept;
// Decodes into `out` (overwritten only when the whole record is valid). expected_index: the
// record's position in the file; a record claiming another index is corrupt.
Status decode_node(const RouteParams& p, Span<const std::uint8_t> in, std::uint32_t expected_index, RouteNode& out,
                   RouteFormatCounters* counters) noexcept;
// Only the record's metadata (still CRC-checked over the whole record).
Status decode_node_meta(const RouteParams& p, Span<const std::uint8_t> in, std::uint32_t expected_index,
                        NodeMeta& out, RouteFormatCounters* counters) noexcept;

// ---- implementation ----
namespace detail {
inline constexpr std::uint8_t kHeaderMagic[8] = {'Q', 'N', 'A', 'V', 'R', 'T', 'E', 0};
inline constexpr std::uint8_t kRecordMagic[4] = {'Q', 'R', 'N', 'D'};

inline void count(RouteFormatCounters* c, RouteFormatCounter e) noexcept {
  if (c != nullptr) c->increment(e);
}
inline bool finite_positive(float v) noexcept { return std::isfinite(v) && v > 0.0f; }
}  // namespace detail


inline Status validate_params(const RouteParams& p) noexcept {
  if (p.sensor != SensorKind::kSideScan && p.sensor != SensorKind::kCamera)
    return Status(StatusCode::kInvalidArgument, "route sensor kind must be sidescan or camera");
  if (p.max_keypoints == 0 || p.max_keypoints > kMaxKeypointsPerNode)
    return Status(StatusCode::kInvalidArgument, "route max_keypoints outside 1..kMaxKeypointsPerNode");
  if (p.descriptor_bytes != kDescriptorBytes) return Status(StatusCode::kUnsupported, "route descriptor size unsupported");
  if (!detail::finite_positive(p.node_spacing_m) || !detail::finite_positive(p.tile_length_m) || !detail::finite_positive(p.tile_width_m) ||
      !detail::finite_positive(p.pixel_m))
    return Status(StatusCode::kInvalidArgument, "route lengths must be finite and positive");
  if (!std::isfinite(p.depth_m) || p.depth_m < 0.0f) return Status(StatusCode::kInvalidArgument, "route depth must be finite, >= 0");
  return Status::ok();
}

inline Status encode_header(const RouteParams& p, Span<std::uint8_t> out) noexcept {
  QNAV_RETURN_IF_ERROR(validate_params(p));
  if (out.size() < kHeaderBytes) return Status(StatusCode::kCapacityExceeded, "header buffer too small");
  std::uint8_t* b = out.data();
  std::memset(b, 0, kHeaderBytes);
  std::memcpy(b, detail::kHeaderMagic, 8);
  store_le_u16(b + 8, kRouteFormatVersion);
  store_le_u16(b + 10, static_cast<std::uint16_t>(kHeaderBytes));
  b[12] = static_cast<std::uint8_t>(p.sensor);
  store_le_u16(b + 14, p.max_keypoints);
  store_le_u16(b + 16, p.descriptor_bytes);
  store_le_u16(b + 18, p.harris_window_px);
  store_le_u16(b + 20, p.keypoint_min_distance_px);
  store_le_f32(b + 24, p.depth_m);
  store_le_f32(b + 28, p.node_spacing_m);
  store_le_f32(b + 32, p.tile_length_m);
  store_le_f32(b + 36, p.tile_width_m);
  store_le_f32(b + 40, p.pixel_m);
  store_le_u32(b + 60, crc32(b, 60));
  return Status::ok();
}

inline Result<RouteParams> decode_header(Span<const std::uint8_t> in, RouteFormatCounters* counters) noexcept {
  if (in.size() < kHeaderBytes) {
    detail::count(counters, RouteFormatCounter::kShortBuffer);
    return Status(StatusCode::kTruncated, "route file shorter than its header");
  }
  const std::uint8_t* b = in.data();
  if (std::memcmp(b, detail::kHeaderMagic, 8) != 0) {
    detail::count(counters, RouteFormatCounter::kBadHeaderMagic);
    return Status(StatusCode::kCorrupt, "not a qnav route file (bad magic)");
  }
  if (load_le_u32(b + 60) != crc32(b, 60)) {
    detail::count(counters, RouteFormatCounter::kBadHeaderCrc);
    return Status(StatusCode::kCorrupt, "route header CRC mismatch");
  }
  if (load_le_u16(b + 8) != kRouteFormatVersion || load_le_u16(b + 10) != kHeaderBytes) {
    detail::count(counters, RouteFormatCounter::kUnsupportedVersion);
    return Status(StatusCode::kUnsupported, "route file version unsupported");
  }
  RouteParams p;
  p.sensor = static_cast<SensorKind>(b[12]);
  p.max_keypoints = load_le_u16(b + 14);
  p.descriptor_bytes = load_le_u16(b + 16);
  p.harris_window_px = load_le_u16(b + 18);
  p.keypoint_min_distance_px = load_le_u16(b + 20);
  p.depth_m = load_le_f32(b + 24);
  p.node_spacing_m = load_le_f32(b + 28);
  p.tile_length_m = load_le_f32(b + 32);
  p.tile_width_m = load_le_f32(b + 36);
  p.pixel_m = load_le_f32(b + 40);
  const Status s = validate_params(p);
  if (!s) {
    detail::count(counters, RouteFormatCounter::kBadParams);
    return s;
  }
  return p;
}

inline Status encode_node(const RouteParams& p, const RouteNode& node, Span<std::uint8_t> out) noexcept {
  const std::size_t n = record_bytes(p.max_keypoints);
  if (p.max_keypoints == 0 || p.max_keypoints > kMaxKeypointsPerNode)
    return Status(StatusCode::kInvalidArgument, "route max_keypoints outside 1..kMaxKeypointsPerNode");
  if (out.size() < n) return Status(StatusCode::kCapacityExceeded, "record buffer too small");
  if (node.keypoints.size() > p.max_keypoints) return Status(StatusCode::kCapacityExceeded, "node has more keypoints than the route allows");
  if (!node.meta.pose.is_finite() || !std::isfinite(node.meta.along_m))
    return Status(StatusCode::kInvalidArgument, "node pose not finite");
  std::uint8_t* b = out.data();
  std::memset(b, 0, n);
  std::memcpy(b, detail::kRecordMagic, 4);
  store_le_u32(b + 4, node.meta.index);
  store_le_f64(b + 8, node.meta.pose.x_m);
  store_le_f64(b + 16, node.meta.pose.y_m);
  store_le_f32(b + 24, static_cast<float>(node.meta.pose.heading_rad));
  store_le_f64(b + 28, node.meta.along_m);
  store_le_u16(b + 36, static_cast<std::uint16_t>(node.keypoints.size()));
  store_le_u64(b + 40, node.meta.stamp_ns);
  std::uint8_t* k = b + kRecordFixedBytes;
  for (const RouteKeypoint& kp : node.keypoints) {
    if (!std::isfinite(kp.x_m) || !std::isfinite(kp.y_m) || !std::isfinite(kp.score))
      return Status(StatusCode::kInvalidArgument, "keypoint not finite");
    store_le_f32(k, kp.x_m);
    store_le_f32(k + 4, kp.y_m);
    store_le_f32(k + 8, kp.score);
    std::memcpy(k + 12, kp.descriptor, kDescriptorBytes);
    k += kKeypointBytes;
  }
  store_le_u32(b + n - 4, crc32(b, n - 4));
  return Status::ok();
}

namespace detail {
inline Status check_record(const RouteParams& p, Span<const std::uint8_t> in, std::uint32_t expected_index, NodeMeta& meta,
                    RouteFormatCounters* counters) noexcept {
  const std::size_t n = record_bytes(p.max_keypoints);
  if (in.size() < n) {
    detail::count(counters, RouteFormatCounter::kShortBuffer);
    return Status(StatusCode::kTruncated, "route record truncated");
  }
  const std::uint8_t* b = in.data();
  if (std::memcmp(b, detail::kRecordMagic, 4) != 0) {
    detail::count(counters, RouteFormatCounter::kBadRecordMagic);
    return Status(StatusCode::kCorrupt, "route record bad magic");
  }
  if (load_le_u32(b + n - 4) != crc32(b, n - 4)) {
    detail::count(counters, RouteFormatCounter::kBadRecordCrc);
    return Status(StatusCode::kCorrupt, "route record CRC mismatch");
  }
  NodeMeta m;
  m.index = load_le_u32(b + 4);
  m.pose.x_m = load_le_f64(b + 8);
  m.pose.y_m = load_le_f64(b + 16);
  m.pose.heading_rad = static_cast<double>(load_le_f32(b + 24));
  m.along_m = load_le_f64(b + 28);
  m.keypoint_count = load_le_u16(b + 36);
  m.stamp_ns = load_le_u64(b + 40);
  if (m.index != expected_index) {
    detail::count(counters, RouteFormatCounter::kBadRecordIndex);
    return Status(StatusCode::kCorrupt, "route record index out of sequence");
  }
  if (m.keypoint_count > p.max_keypoints || !m.pose.is_finite() || !std::isfinite(m.along_m)) {
    detail::count(counters, RouteFormatCounter::kBadRecordField);
    return Status(StatusCode::kCorrupt, "route record field out of range");
  }
  meta = m;
  return Status::ok();
}
}  // namespace detail

inline Status decode_node_meta(const RouteParams& p, Span<const std::uint8_t> in, std::uint32_t expected_index,
                        NodeMeta& out, RouteFormatCounters* counters) noexcept {
  return detail::check_record(p, in, expected_index, out, counters);
}

inline Status decode_node(const RouteParams& p, Span<const std::uint8_t> in, std::uint32_t expected_index, RouteNode& out,
                   RouteFormatCounters* counters) noexcept {
  NodeMeta meta;
  QNAV_RETURN_IF_ERROR(detail::check_record(p, in, expected_index, meta, counters));
  const std::uint8_t* k = in.data() + kRecordFixedBytes;
  for (std::size_t i = 0; i < meta.keypoint_count; ++i, k += kKeypointBytes) {
    if (!std::isfinite(load_le_f32(k)) || !std::isfinite(load_le_f32(k + 4)) || !std::isfinite(load_le_f32(k + 8))) {
      detail::count(counters, RouteFormatCounter::kBadRecordField);
      return Status(StatusCode::kCorrupt, "route keypoint not finite");
    }
  }
  out.meta = meta;
  out.keypoints.clear();
  k = in.data() + kRecordFixedBytes;
  for (std::size_t i = 0; i < meta.keypoint_count; ++i, k += kKeypointBytes) {
    RouteKeypoint* kp = out.keypoints.emplace_back();
    kp->x_m = load_le_f32(k);
    kp->y_m = load_le_f32(k + 4);
    kp->score = load_le_f32(k + 8);
    std::memcpy(kp->descriptor, k + 12, kDescriptorBytes);
  }
  return Status::ok();
}

}  // namespace qnav::route
