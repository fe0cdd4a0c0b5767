// The route file format (version 2): byte-level encode and decode with CRC-32. No I/O here: the
// fsync'ing writer and the bounded reader live in drivers/route_store/route_file.{hpp,cpp}.
//
// Layout (all multi-byte fields little-endian, floats IEEE-754; decoded with nav/core/byte_order):
//   header, kHeaderBytes = 64:
//     0  char[8]  magic "QNAVRTE\0"     8  u16 version (2; 1 is read) 10 u16 header_bytes (64)
//     12 u8 sensor_kind  13 u8 reserved 14 u16 max_keypoints     16 u16 descriptor_bytes (64)
//     18 u16 harris_window_px           20 u16 keypoint_min_distance_px   22 u16 reserved
//     24 f32 depth_m  28 f32 node_spacing_m  32 f32 tile_length_m  36 f32 tile_width_m
//     40 f32 pixel_m  44..59 reserved (zero)                       60 u32 crc32 of bytes 0..59
//   then one fixed-size record per node, record_bytes(max_keypoints):
//     0 u32 magic "QRND"  4 u32 node_index  8 f64 x_m  16 f64 y_m  24 f32 heading_rad
//     28 f64 along_m  36 u16 keypoint_count  38 u16 reserved  40 u64 stamp_ns
//     48 max_keypoints x { f32 x_m, f32 y_m, f32 score, i8[64] descriptor } (unused slots zero)
//     last 4 bytes: u32 crc32 of everything before it in the record.
//   then, only when the writer closed the route deliberately (close / commit), the end mark,
//   kEndMarkBytes = 16, right after the last record:
//     0 u32 magic "QEND"  4 u32 node_count (records before it)  8 u32 reserved (zero)
//     12 u32 crc32 of bytes 0..11
// Fixed-size records make node i addressable at header + i * record_bytes (bounded reads of any
// node without an index) and make a torn tail visible as a file length that is not a whole number
// of records. The end mark is shorter than any record (record_bytes >= 128), so a file ends either
// on a record boundary (cut off: no end mark), 16 bytes after one with a valid mark (closed cleanly,
// if its count agrees) or anywhere else (a torn tail). The mark is appended, never written into the
// header: a rewrite in place that a power cut tore would lose the whole route's header. Reopening a
// route to append cuts the mark (or a torn tail) off first. Version 1 (the same header and records,
// no end mark) is still read; its files cannot tell a complete route from a cut-off one.
// Every decode checks magic, CRC, index, counts, finiteness and bounds of every field (node pose and
// along-track distance within kMaxRouteCoordinateM, heading within kMaxHeadingRad, keypoint
// positions within kMaxKeypointOffsetPx tile pixels of the tile centre): a damaged record is reported
// (kCorrupt + counter), never half-used. encode_node refuses the same values, so no writer can put
// a record on the medium that a reader would reject. Cost O(record bytes), no heap.
#pragma once

#include <cstddef>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "nav/core/byte_order.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/crc.hpp"
#include "nav/core/image.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::route {

constexpr std::uint16_t kRouteFormatVersion = 2;       // written
constexpr std::uint16_t kOldestRouteFormatVersion = 1;  // still read (no end mark)
constexpr std::size_t kHeaderBytes = 64;
constexpr std::size_t kRecordFixedBytes = 48;
constexpr std::size_t kKeypointBytes = 12 + kDescriptorBytes;
constexpr std::size_t kEndMarkBytes = 16;

// Bounds of the values a record may hold (beyond them a value is damage, not data):
// route-frame positions and along-track distances (half the Earth's circumference),
constexpr double kMaxRouteCoordinateM = 2.0e7;
// headings (f32: 1024 rad still resolves 0.0035 deg; unwrapped headings of 160 turns fit),
constexpr double kMaxHeadingRad = 1024.0;
// keypoint positions from the tile centre, in tile pixels (pixel_m): no tile raster is wider than
// kMaxImageSide, so no keypoint of one lies further than its diagonal from its centre,
constexpr double kMaxKeypointOffsetPx = 1.5 * static_cast<double>(kMaxImageSide);
// header lengths (node spacing, tile size, pixel) and depth (the deepest ocean is 11 km).
constexpr float kMaxRouteLengthParamM = 1.0e5f;
constexpr float kMaxRouteDepthM = 12000.0f;

enum class RouteFormatCounter : std::uint8_t {
  kBadHeaderMagic, kBadHeaderCrc, kUnsupportedVersion, kBadParams,
  kBadRecordMagic, kBadRecordCrc, kBadRecordIndex, kBadRecordField, kShortBuffer,
  kTornTail, kNoEndMark, kBadEndMark, kCount
};
inline constexpr const char* kRouteFormatCounterNames[] = {
    "bad_header_magic", "bad_header_crc", "unsupported_version", "bad_params",
    "bad_record_magic", "bad_record_crc", "bad_record_index", "bad_record_field", "short_buffer",
    "torn_tail", "no_end_mark", "bad_end_mark"};
using RouteFormatCounters = CounterSet<RouteFormatCounter>;

// Bytes of one node record for a route with max_keypoints slots.
constexpr std::size_t record_bytes(std::size_t max_keypoints) noexcept {
  return kRecordFixedBytes + max_keypoints * kKeypointBytes + 4;
}
static_assert(record_bytes(1) > kEndMarkBytes, "the end mark must be shorter than any record");

// What a header says beyond the route's parameters.
struct RouteHeaderInfo {
  std::uint16_t version = kRouteFormatVersion;
};

// Checks parameters a writer may put in a header (sizes within bounds, finite positive lengths).
Status validate_params(const RouteParams& p) noexcept;
// Checks a node a writer may put in a record (keypoint count, every field finite and within the
// bounds above). The decoders apply the same checks to what they read.
Status validate_node(const RouteParams& p, const RouteNode& node) noexcept;

// out.size() >= kHeaderBytes. Always writes kRouteFormatVersion.
Status encode_header(const RouteParams& p, Span<std::uint8_t> out) noexcept;
// Reads version 1 and 2 headers; info (optional) receives the version.
Result<RouteParams> decode_header(Span<const std::uint8_t> in, RouteFormatCounters* counters,
                                  RouteHeaderInfo* info = nullptr) noexcept;

// out.size() >= record_bytes(p.max_keypoints); node.keypoints.size() <= p.max_keypoints. Refuses a
// node validate_node refuses, before writing anything to out.
Status encode_node(const RouteParams& p, const RouteNode& node, Span<std::uint8_t> out) noexcept;
// Decodes into `out` (overwritten only when the whole record is valid). expected_index: the
// record's position in the file; a record claiming another index is corrupt.
Status decode_node(const RouteParams& p, Span<const std::uint8_t> in, std::uint32_t expected_index, RouteNode& out,
                   RouteFormatCounters* counters) noexcept;
// Only the record's metadata, after the same checks as decode_node (CRC over the whole record and
// every field, keypoints included): a record this accepts, decode_node accepts.
Status decode_node_meta(const RouteParams& p, Span<const std::uint8_t> in, std::uint32_t expected_index,
                        NodeMeta& out, RouteFormatCounters* counters) noexcept;

// The end mark after node_count records. out.size() >= kEndMarkBytes.
Status encode_end_mark(std::uint32_t node_count, Span<std::uint8_t> out) noexcept;
// A valid end mark's node count; kCorrupt (+ bad_end_mark) when the bytes are not one.
Result<std::uint32_t> decode_end_mark(Span<const std::uint8_t> in, RouteFormatCounters* counters) noexcept;

// ---- implementation ----
namespace detail {
inline constexpr std::uint8_t kHeaderMagic[8] = {'Q', 'N', 'A', 'V', 'R', 'T', 'E', 0};
inline constexpr std::uint8_t kRecordMagic[4] = {'Q', 'R', 'N', 'D'};
inline constexpr std::uint8_t kEndMagic[4] = {'Q', 'E', 'N', 'D'};

inline void count(RouteFormatCounters* c, RouteFormatCounter e) noexcept {
  if (c != nullptr) c->increment(e);
}
inline bool finite_positive(float v) noexcept { return std::isfinite(v) && v > 0.0f; }
inline bool within(double v, double bound) noexcept { return std::isfinite(v) && std::fabs(v) <= bound; }

// nullptr when the metadata is within bounds, else why not.
inline const char* meta_problem(const RouteParams& p, const NodeMeta& m) noexcept {
  if (!m.pose.is_finite() || !std::isfinite(m.along_m)) return "route node pose not finite";
  if (!within(m.pose.x_m, kMaxRouteCoordinateM) || !within(m.pose.y_m, kMaxRouteCoordinateM) ||
      !within(m.along_m, kMaxRouteCoordinateM))
    return "route node position out of range";
  if (!within(m.pose.heading_rad, kMaxHeadingRad)) return "route node heading out of range";
  if (m.keypoint_count > p.max_keypoints) return "route node has more keypoints than the route allows";
  return nullptr;
}
inline const char* keypoint_problem(const RouteParams& p, float x_m, float y_m, float score) noexcept {
  if (!std::isfinite(x_m) || !std::isfinite(y_m) || !std::isfinite(score)) return "route keypoint not finite";
  const double bound = kMaxKeypointOffsetPx * static_cast<double>(p.pixel_m);
  if (!within(static_cast<double>(x_m), bound) || !within(static_cast<double>(y_m), bound)) return "route keypoint position out of range";
  return nullptr;
}
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
  if (p.node_spacing_m > kMaxRouteLengthParamM || p.tile_length_m > kMaxRouteLengthParamM || p.tile_width_m > kMaxRouteLengthParamM ||
      p.pixel_m > kMaxRouteLengthParamM)
    return Status(StatusCode::kInvalidArgument, "route lengths must be <= 100 km");
  if (!std::isfinite(p.depth_m) || p.depth_m < 0.0f || p.depth_m > kMaxRouteDepthM)
    return Status(StatusCode::kInvalidArgument, "route depth must be finite, 0..12000 m");
  return Status::ok();
}

inline Status validate_node(const RouteParams& p, const RouteNode& node) noexcept {
  if (p.max_keypoints == 0 || p.max_keypoints > kMaxKeypointsPerNode)
    return Status(StatusCode::kInvalidArgument, "route max_keypoints outside 1..kMaxKeypointsPerNode");
  if (node.keypoints.size() > p.max_keypoints) return Status(StatusCode::kCapacityExceeded, "node has more keypoints than the route allows");
  NodeMeta m = node.meta;
  m.keypoint_count = static_cast<std::uint16_t>(node.keypoints.size());
  if (const char* why = detail::meta_problem(p, m)) return Status(StatusCode::kInvalidArgument, why);
  for (const RouteKeypoint& kp : node.keypoints)
    if (const char* why = detail::keypoint_problem(p, kp.x_m, kp.y_m, kp.score)) return Status(StatusCode::kInvalidArgument, why);
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

inline Result<RouteParams> decode_header(Span<const std::uint8_t> in, RouteFormatCounters* counters, RouteHeaderInfo* info) noexcept {
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
  const std::uint16_t version = load_le_u16(b + 8);
  if (version < kOldestRouteFormatVersion || version > kRouteFormatVersion || load_le_u16(b + 10) != kHeaderBytes) {
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
  if (info != nullptr) info->version = version;
  return p;
}

inline Status encode_node(const RouteParams& p, const RouteNode& node, Span<std::uint8_t> out) noexcept {
  QNAV_RETURN_IF_ERROR(validate_node(p, node));
  const std::size_t n = record_bytes(p.max_keypoints);
  if (out.size() < n) return Status(StatusCode::kCapacityExceeded, "record buffer too small");
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
  // A CRC-valid record can still hold values no writer of this format puts there (an older or
  // foreign writer, or damage the CRC missed): the same checks as validate_node.
  const char* why = detail::meta_problem(p, m);
  const std::uint8_t* k = b + kRecordFixedBytes;
  for (std::size_t i = 0; why == nullptr && i < m.keypoint_count; ++i, k += kKeypointBytes)
    why = detail::keypoint_problem(p, load_le_f32(k), load_le_f32(k + 4), load_le_f32(k + 8));
  if (why != nullptr) {
    detail::count(counters, RouteFormatCounter::kBadRecordField);
    return Status(StatusCode::kCorrupt, why);
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
  out.meta = meta;
  out.keypoints.clear();
  const std::uint8_t* k = in.data() + kRecordFixedBytes;
  for (std::size_t i = 0; i < meta.keypoint_count; ++i, k += kKeypointBytes) {
    RouteKeypoint* kp = out.keypoints.emplace_back();
    kp->x_m = load_le_f32(k);
    kp->y_m = load_le_f32(k + 4);
    kp->score = load_le_f32(k + 8);
    std::memcpy(kp->descriptor, k + 12, kDescriptorBytes);
  }
  return Status::ok();
}

inline Status encode_end_mark(std::uint32_t node_count, Span<std::uint8_t> out) noexcept {
  if (out.size() < kEndMarkBytes) return Status(StatusCode::kCapacityExceeded, "end mark buffer too small");
  std::uint8_t* b = out.data();
  std::memset(b, 0, kEndMarkBytes);
  std::memcpy(b, detail::kEndMagic, 4);
  store_le_u32(b + 4, node_count);
  store_le_u32(b + 12, crc32(b, 12));
  return Status::ok();
}

inline Result<std::uint32_t> decode_end_mark(Span<const std::uint8_t> in, RouteFormatCounters* counters) noexcept {
  const std::uint8_t* b = in.data();
  if (in.size() < kEndMarkBytes || std::memcmp(b, detail::kEndMagic, 4) != 0 || load_le_u32(b + 8) != 0 ||
      load_le_u32(b + 12) != crc32(b, 12)) {
    detail::count(counters, RouteFormatCounter::kBadEndMark);
    return Status(StatusCode::kCorrupt, "route end mark damaged");
  }
  return load_le_u32(b + 4);
}

}  // namespace qnav::route
