// The topological map file format (version 1): byte-level encode and decode with CRC-32, like the
// route file (nav/route/route_format.hpp). No I/O here: the writer and reader on a hal::FileStore
// are firmware/tools/map_file.{hpp,cpp}.
//
// Layout (all multi-byte fields little-endian, floats IEEE-754; nav/core/byte_order):
//   header, kMapHeaderBytes = 64:
//     0  char[8] magic "QNAVTOPO"   8 u16 version (1)   10 u16 header_bytes (64)
//     12 u16 signature_bins (64)    14 u16 node_record_bytes (304)   16 u16 edge_record_bytes (12)
//     18 u16 max_edges_per_node     20 u32 node_count   24 u32 edge_count   28 u32 capacity (max_nodes)
//     32 u32 observations           36 u32 revisits     40 f64 node_spacing
//     48 u8 units (0 = mosaic pixels, 1 = metres)       49..59 reserved (zero)
//     60 u32 crc32 of bytes 0..59
//   node_count node records, kMapNodeBytes = 304, ids increasing:
//     0 u32 magic "QTND"  4 u16 id  6 u16 reserved  8 f64 x  16 f64 y  24 f32 heading_rad
//     28 u32 created  32 u32 last_seen  36 u32 visits  40 u32 revisits  44 f32 bins[64]
//     300 u32 crc32 of bytes 0..299
//   edge_count edge records, kMapEdgeBytes = 12 (each undirected edge once, a < b):
//     0 u16 a  2 u16 b  4 u16 age  6 u16 reserved  8 u32 crc32 of bytes 0..7
// The file is exactly header + nodes + edges bytes: anything else is truncated or has trailing bytes.
// Every decode checks magic, CRC, sizes and the values (finite, signature bins in [0, 1], ids below
// the capacity): a damaged file is refused with the check that failed, never half-read. Cost
// O(record bytes), no heap.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "nav/core/byte_order.hpp"
#include "nav/core/crc.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/topo/topo_map.hpp"

namespace qnav::topo {

constexpr std::uint16_t kMapFormatVersion = 1;
constexpr std::size_t kMapHeaderBytes = 64;
constexpr std::size_t kMapNodeBytes = 44 + 4 * kSignatureBins + 4;
constexpr std::size_t kMapEdgeBytes = 12;
static_assert(kMapNodeBytes == 304, "node record layout");
constexpr double kMaxMapCoordinate = 1.0e9;  // metres or pixels; beyond: damage, not data

struct MapHeader {
  std::uint16_t version = kMapFormatVersion;
  std::uint16_t max_edges_per_node = 0;
  std::uint32_t node_count = 0;
  std::uint32_t edge_count = 0;
  std::uint32_t capacity = 0;
  std::uint32_t observations = 0;
  std::uint32_t revisits = 0;
  double node_spacing = 0.0;
  bool metric = false;
};

constexpr std::uint64_t map_file_bytes(std::uint64_t nodes, std::uint64_t edges) noexcept {
  return kMapHeaderBytes + nodes * kMapNodeBytes + edges * kMapEdgeBytes;
}

namespace detail {
inline constexpr std::uint8_t kMapMagic[8] = {'Q', 'N', 'A', 'V', 'T', 'O', 'P', 'O'};
inline constexpr std::uint8_t kMapNodeMagic[4] = {'Q', 'T', 'N', 'D'};
}  // namespace detail

inline Status encode_map_header(const MapHeader& h, Span<std::uint8_t> out) noexcept {
  if (out.size() < kMapHeaderBytes) return Status(StatusCode::kCapacityExceeded, "map header buffer too small");
  if (!std::isfinite(h.node_spacing) || !(h.node_spacing > 0.0) || h.capacity == 0 || h.capacity >= kNoNode ||
      h.node_count > h.capacity)
    return Status(StatusCode::kInvalidArgument, "map header: spacing, capacity or node count out of range");
  std::uint8_t* b = out.data();
  std::memset(b, 0, kMapHeaderBytes);
  std::memcpy(b, detail::kMapMagic, 8);
  store_le_u16(b + 8, kMapFormatVersion);
  store_le_u16(b + 10, static_cast<std::uint16_t>(kMapHeaderBytes));
  store_le_u16(b + 12, static_cast<std::uint16_t>(kSignatureBins));
  store_le_u16(b + 14, static_cast<std::uint16_t>(kMapNodeBytes));
  store_le_u16(b + 16, static_cast<std::uint16_t>(kMapEdgeBytes));
  store_le_u16(b + 18, h.max_edges_per_node);
  store_le_u32(b + 20, h.node_count);
  store_le_u32(b + 24, h.edge_count);
  store_le_u32(b + 28, h.capacity);
  store_le_u32(b + 32, h.observations);
  store_le_u32(b + 36, h.revisits);
  store_le_f64(b + 40, h.node_spacing);
  b[48] = h.metric ? 1 : 0;
  store_le_u32(b + 60, crc32(b, 60));
  return Status::ok();
}

inline Status decode_map_header(Span<const std::uint8_t> in, MapHeader& out) noexcept {
  if (in.size() < kMapHeaderBytes) return Status(StatusCode::kTruncated, "map file shorter than its header");
  const std::uint8_t* b = in.data();
  if (std::memcmp(b, detail::kMapMagic, 8) != 0) return Status(StatusCode::kCorrupt, "not a qnav map file (bad magic)");
  if (load_le_u32(b + 60) != crc32(b, 60)) return Status(StatusCode::kCorrupt, "map header CRC mismatch");
  if (load_le_u16(b + 8) != kMapFormatVersion || load_le_u16(b + 10) != kMapHeaderBytes)
    return Status(StatusCode::kUnsupported, "map file version unsupported");
  if (load_le_u16(b + 12) != kSignatureBins || load_le_u16(b + 14) != kMapNodeBytes || load_le_u16(b + 16) != kMapEdgeBytes)
    return Status(StatusCode::kUnsupported, "map file record layout unsupported (signature or record sizes)");
  MapHeader h;
  h.version = load_le_u16(b + 8);
  h.max_edges_per_node = load_le_u16(b + 18);
  h.node_count = load_le_u32(b + 20);
  h.edge_count = load_le_u32(b + 24);
  h.capacity = load_le_u32(b + 28);
  h.observations = load_le_u32(b + 32);
  h.revisits = load_le_u32(b + 36);
  h.node_spacing = load_le_f64(b + 40);
  h.metric = b[48] != 0;
  if (b[48] > 1 || !std::isfinite(h.node_spacing) || !(h.node_spacing > 0.0) || h.capacity == 0 || h.capacity >= kNoNode ||
      h.node_count > h.capacity || h.max_edges_per_node == 0 || h.max_edges_per_node > kMaxEdgesPerNode ||
      h.edge_count > static_cast<std::uint64_t>(h.node_count) * h.max_edges_per_node / 2)
    return Status(StatusCode::kCorrupt, "map header fields out of range");
  out = h;
  return Status::ok();
}

inline Status encode_map_node(std::uint16_t id, const TopoNode& n, Span<std::uint8_t> out) noexcept {
  if (out.size() < kMapNodeBytes) return Status(StatusCode::kCapacityExceeded, "map node buffer too small");
  if (!n.position.allFinite() || std::fabs(n.position.x()) > kMaxMapCoordinate || std::fabs(n.position.y()) > kMaxMapCoordinate ||
      !std::isfinite(n.heading_rad))
    return Status(StatusCode::kInvalidArgument, "map node pose not finite or out of range");
  std::uint8_t* b = out.data();
  std::memset(b, 0, kMapNodeBytes);
  std::memcpy(b, detail::kMapNodeMagic, 4);
  store_le_u16(b + 4, id);
  store_le_f64(b + 8, n.position.x());
  store_le_f64(b + 16, n.position.y());
  store_le_f32(b + 24, static_cast<float>(n.heading_rad));
  store_le_u32(b + 28, n.created);
  store_le_u32(b + 32, n.last_seen);
  store_le_u32(b + 36, n.visits);
  store_le_u32(b + 40, n.revisits);
  for (int i = 0; i < kSignatureBins; ++i) store_le_f32(b + 44 + 4 * i, n.signature.bins[i]);
  store_le_u32(b + kMapNodeBytes - 4, crc32(b, kMapNodeBytes - 4));
  return Status::ok();
}

inline Status decode_map_node(Span<const std::uint8_t> in, std::uint16_t& id, TopoNode& out) noexcept {
  if (in.size() < kMapNodeBytes) return Status(StatusCode::kTruncated, "map node record truncated");
  const std::uint8_t* b = in.data();
  if (std::memcmp(b, detail::kMapNodeMagic, 4) != 0) return Status(StatusCode::kCorrupt, "map node record bad magic");
  if (load_le_u32(b + kMapNodeBytes - 4) != crc32(b, kMapNodeBytes - 4)) return Status(StatusCode::kCorrupt, "map node record CRC mismatch");
  TopoNode n;
  id = load_le_u16(b + 4);
  n.position = Vec2d(load_le_f64(b + 8), load_le_f64(b + 16));
  n.heading_rad = static_cast<double>(load_le_f32(b + 24));
  n.created = load_le_u32(b + 28);
  n.last_seen = load_le_u32(b + 32);
  n.visits = load_le_u32(b + 36);
  n.revisits = load_le_u32(b + 40);
  float sum = 0.0f;
  bool ok = n.position.allFinite() && std::fabs(n.position.x()) <= kMaxMapCoordinate &&
            std::fabs(n.position.y()) <= kMaxMapCoordinate && std::isfinite(n.heading_rad) && id != kNoNode;
  for (int i = 0; i < kSignatureBins; ++i) {
    const float v = load_le_f32(b + 44 + 4 * i);
    ok = ok && std::isfinite(v) && v >= 0.0f && v <= 1.0f;
    n.signature.bins[i] = v;
    sum += v;
  }
  if (!ok) return Status(StatusCode::kCorrupt, "map node record fields out of range");
  n.signature.words = sum > 0.0f ? 1u : 0u;
  out = n;
  return Status::ok();
}

inline Status encode_map_edge(std::uint16_t a, std::uint16_t b, std::uint16_t age, Span<std::uint8_t> out) noexcept {
  if (out.size() < kMapEdgeBytes) return Status(StatusCode::kCapacityExceeded, "map edge buffer too small");
  std::uint8_t* p = out.data();
  std::memset(p, 0, kMapEdgeBytes);
  store_le_u16(p, a);
  store_le_u16(p + 2, b);
  store_le_u16(p + 4, age);
  store_le_u32(p + 8, crc32(p, 8));
  return Status::ok();
}

inline Status decode_map_edge(Span<const std::uint8_t> in, std::uint16_t& a, std::uint16_t& b, std::uint16_t& age) noexcept {
  if (in.size() < kMapEdgeBytes) return Status(StatusCode::kTruncated, "map edge record truncated");
  const std::uint8_t* p = in.data();
  if (load_le_u32(p + 8) != crc32(p, 8) || load_le_u16(p + 6) != 0) return Status(StatusCode::kCorrupt, "map edge record CRC mismatch");
  a = load_le_u16(p);
  b = load_le_u16(p + 2);
  age = load_le_u16(p + 4);
  return Status::ok();
}

}  // namespace qnav::topo
