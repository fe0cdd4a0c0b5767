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
#include <cstdint>

#include "nav/core/counters.hpp"
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

}  // namespace qnav::route
