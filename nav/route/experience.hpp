// Route experiences (multi-experience localisation, issue 29): what a repeat saw of a taught node,
// kept beside the taught keypoints so the next repeat registers against both.
//  - Experience: the keypoints of a repeat tile that was localised with confidence, carried into the
//    node's tile frame by that registration (so registering a new tile against an experience gives
//    the pose in the node's frame, exactly as against the taught keypoints), with the pass's
//    direction, its offset from the node, its id and the tile's time.
//  - The experience file format (version 1), byte-level encode / decode + CRC-32, no I/O (the durable
//    store is drivers/route_store/experience_file.hpp). It is a companion of the route file
//    (ROUTE.exp), not a part of it: route files keep format 2 (bit for bit as before), every reader
//    before this change ignores the companion (it never opens it), and a route without one is a route
//    without experiences. Layout (little-endian, floats IEEE-754, nav/core/byte_order):
//      header, kExpHeaderBytes = 64:
//        0 char[8] magic "QNAVREX\0"  8 u16 version (1)  10 u16 header_bytes (64)  12 u16 max_keypoints
//        14 u16 max_per_node  16 u32 route_header_crc  20 u32 route_node0_crc  24..59 reserved (zero)
//        60 u32 crc32 of bytes 0..59
//      then one fixed-size record per experience, exp_record_bytes(max_keypoints) (= the route's node
//      record size):
//        0 u32 magic "QREX"  4 u32 record (its position in the file)  8 u32 node  12 u16 slot
//        14 u8 reverse  15 u8 reserved  16 f32 offset_m  20 u32 pass_id  24 u64 stamp_ns
//        32 u16 keypoint_count  34 u16 inliers  36 f32 node_heading_rad  40..47 reserved (zero)
//        48 max_keypoints x { f32 x_m, f32 y_m, f32 score, i8[64] descriptor } (unused slots zero)
//        last 4 bytes: u32 crc32 of everything before it.
//    The binding (route_header_crc = CRC-32 of the route header as this code encodes it,
//    route_node0_crc = node 0's record CRC as encoded) ties the companion to one teach: a route
//    taught again (same parameters, other nodes) does not take the old route's experiences.
//    Records are only appended: a later record for the same (node, slot) replaces the earlier one;
//    compaction rewrites the file with the live records only, renumbered in their order (so
//    "smaller record = learned earlier" still holds).
//  - ExperienceIndex: per node, up to max_per_node slots (record number, pass id, direction, offset);
//    fixed memory nodes x max_per_node x sizeof(ExperienceSlot) from an Arena. Replacement rule
//    (choose_slot): an empty slot first; when all are full, the oldest experience (smallest record)
//    that was not this pass's best match on the node; the taught keypoints are never replaced (they
//    live in the route file).
// Cost: encode / decode O(record bytes); index operations O(max_per_node). No heap.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "nav/core/arena.hpp"
#include "nav/core/byte_order.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/crc.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/route/route_format.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::route {

constexpr std::uint16_t kExperienceFormatVersion = 1;
constexpr std::size_t kExpHeaderBytes = 64;
constexpr std::size_t kExpRecordFixedBytes = 48;
// Most experiences one node may hold (the configuration chooses up to this).
constexpr std::size_t kMaxExperiencesPerNode = 8;
constexpr std::uint32_t kNoExperience = 0xFFFFFFFFu;

constexpr std::size_t exp_record_bytes(std::size_t max_keypoints) noexcept {
  return kExpRecordFixedBytes + max_keypoints * kKeypointBytes + 4;
}
static_assert(exp_record_bytes(1) == record_bytes(1), "experience records are the size of node records");

struct ExperienceMeta {
  std::uint32_t record = 0;      // position in the experience file (larger = learned later)
  std::uint32_t node = 0;        // the taught node it belongs to
  std::uint16_t slot = 0;        // 0..max_per_node-1
  bool reverse = false;          // the learning pass ran the route backwards
  float offset_m = 0.0f;         // the learned tile's origin across the node's track (node frame y), m
  std::uint32_t pass_id = 0;     // the learning pass (1..; 0 is the taught pass)
  std::uint64_t stamp_ns = 0;    // sample time of the learned tile
  std::uint16_t inliers = 0;     // registration inliers when it was learned
  std::uint16_t keypoint_count = 0;
  float node_heading_rad = 0.0f; // the node's tile heading (the frame the keypoints are in)
};

// keypoints in the node's tile frame; node.meta.index = meta.node, node.meta.pose.heading_rad =
// meta.node_heading_rad (what the registrar compares the compass with).
struct Experience {
  ExperienceMeta meta;
  RouteNode node;
};

enum class ExperienceFormatCounter : std::uint8_t {
  kBadHeaderMagic, kBadHeaderCrc, kUnsupportedVersion, kBadHeader, kOtherRoute,
  kBadRecordMagic, kBadRecordCrc, kBadRecordIndex, kBadRecordField, kShortBuffer, kTornTail, kCount
};
inline constexpr const char* kExperienceFormatCounterNames[] = {
    "bad_header_magic", "bad_header_crc", "unsupported_version", "bad_header", "other_route",
    "bad_record_magic", "bad_record_crc", "bad_record_index", "bad_record_field", "short_buffer", "torn_tail"};
using ExperienceFormatCounters = CounterSet<ExperienceFormatCounter>;

struct ExperienceHeader {
  std::uint16_t version = kExperienceFormatVersion;
  std::uint16_t max_keypoints = 0;
  std::uint16_t max_per_node = 0;
  std::uint32_t route_header_crc = 0;
  std::uint32_t route_node0_crc = 0;
};

// The binding of a route (see above): CRC-32 of its header and of node 0's record, as encoded.
// scratch.size() >= record_bytes(params.max_keypoints).
inline Status route_binding(const RouteParams& params, const RouteNode& node0, Span<std::uint8_t> scratch, std::uint32_t& header_crc,
                            std::uint32_t& node0_crc) noexcept {
  std::uint8_t h[kHeaderBytes];
  QNAV_RETURN_IF_ERROR(encode_header(params, Span<std::uint8_t>(h)));
  header_crc = crc32(h, kHeaderBytes);
  RouteNode n0 = node0;
  n0.meta.index = 0;
  QNAV_RETURN_IF_ERROR(encode_node(params, n0, scratch));
  node0_crc = load_le_u32(scratch.data() + record_bytes(params.max_keypoints) - 4);  // the record's own CRC
  return Status::ok();
}

inline Status encode_exp_header(const ExperienceHeader& h, Span<std::uint8_t> out) noexcept {
  if (out.size() < kExpHeaderBytes) return Status(StatusCode::kCapacityExceeded, "experience header buffer too small");
  if (h.max_keypoints == 0 || h.max_keypoints > kMaxKeypointsPerNode || h.max_per_node == 0 || h.max_per_node > kMaxExperiencesPerNode)
    return Status(StatusCode::kInvalidArgument, "experience header: max_keypoints or max_per_node out of range");
  std::uint8_t* b = out.data();
  std::memset(b, 0, kExpHeaderBytes);
  std::memcpy(b, "QNAVREX", 8);
  store_le_u16(b + 8, kExperienceFormatVersion);
  store_le_u16(b + 10, static_cast<std::uint16_t>(kExpHeaderBytes));
  store_le_u16(b + 12, h.max_keypoints);
  store_le_u16(b + 14, h.max_per_node);
  store_le_u32(b + 16, h.route_header_crc);
  store_le_u32(b + 20, h.route_node0_crc);
  store_le_u32(b + 60, crc32(b, 60));
  return Status::ok();
}

inline Result<ExperienceHeader> decode_exp_header(Span<const std::uint8_t> in, ExperienceFormatCounters* c) noexcept {
  auto count = [c](ExperienceFormatCounter e) {
    if (c != nullptr) c->increment(e);
  };
  if (in.size() < kExpHeaderBytes) {
    count(ExperienceFormatCounter::kShortBuffer);
    return Status(StatusCode::kTruncated, "experience file shorter than its header");
  }
  const std::uint8_t* b = in.data();
  if (std::memcmp(b, "QNAVREX", 8) != 0) {
    count(ExperienceFormatCounter::kBadHeaderMagic);
    return Status(StatusCode::kCorrupt, "not a qnav experience file (bad magic)");
  }
  if (load_le_u32(b + 60) != crc32(b, 60)) {
    count(ExperienceFormatCounter::kBadHeaderCrc);
    return Status(StatusCode::kCorrupt, "experience header CRC mismatch");
  }
  ExperienceHeader h;
  h.version = load_le_u16(b + 8);
  if (h.version != kExperienceFormatVersion || load_le_u16(b + 10) != kExpHeaderBytes) {
    count(ExperienceFormatCounter::kUnsupportedVersion);
    return Status(StatusCode::kUnsupported, "experience file version unsupported");
  }
  h.max_keypoints = load_le_u16(b + 12);
  h.max_per_node = load_le_u16(b + 14);
  h.route_header_crc = load_le_u32(b + 16);
  h.route_node0_crc = load_le_u32(b + 20);
  if (h.max_keypoints == 0 || h.max_keypoints > kMaxKeypointsPerNode || h.max_per_node == 0 || h.max_per_node > kMaxExperiencesPerNode) {
    count(ExperienceFormatCounter::kBadHeader);
    return Status(StatusCode::kCorrupt, "experience header: max_keypoints or max_per_node out of range");
  }
  return h;
}

namespace detail {
// nullptr when the experience's fields are within bounds (node_count: the route's), else why not.
inline const char* experience_problem(const RouteParams& p, const ExperienceHeader& h, std::uint32_t node_count, const ExperienceMeta& m) noexcept {
  if (m.node >= node_count) return "experience node beyond the route";
  if (m.slot >= h.max_per_node) return "experience slot beyond max_per_node";
  if (m.keypoint_count > h.max_keypoints || m.keypoint_count > p.max_keypoints) return "experience has more keypoints than the route allows";
  if (!within(static_cast<double>(m.offset_m), kMaxRouteCoordinateM)) return "experience offset not finite or out of range";
  if (!within(static_cast<double>(m.node_heading_rad), kMaxHeadingRad)) return "experience heading not finite or out of range";
  if (m.pass_id == 0) return "experience pass id 0 (the taught pass)";
  return nullptr;
}
}  // namespace detail

// Refuses (before writing a byte) what a reader would refuse. node_count: the route's nodes.
inline Status encode_experience(const RouteParams& p, const ExperienceHeader& h, std::uint32_t node_count, const Experience& e,
                                Span<std::uint8_t> out) noexcept {
  const std::size_t n = exp_record_bytes(h.max_keypoints);
  if (out.size() < n) return Status(StatusCode::kCapacityExceeded, "experience record buffer too small");
  ExperienceMeta m = e.meta;
  m.keypoint_count = static_cast<std::uint16_t>(e.node.keypoints.size());
  if (e.node.keypoints.size() > h.max_keypoints) return Status(StatusCode::kCapacityExceeded, "experience has more keypoints than the file allows");
  if (const char* why = detail::experience_problem(p, h, node_count, m)) return Status(StatusCode::kInvalidArgument, why);
  for (const RouteKeypoint& kp : e.node.keypoints)
    if (const char* why = detail::keypoint_problem(p, kp.x_m, kp.y_m, kp.score)) return Status(StatusCode::kInvalidArgument, why);
  std::uint8_t* b = out.data();
  std::memset(b, 0, n);
  std::memcpy(b, "QREX", 4);
  store_le_u32(b + 4, m.record);
  store_le_u32(b + 8, m.node);
  store_le_u16(b + 12, m.slot);
  b[14] = m.reverse ? 1 : 0;
  store_le_f32(b + 16, m.offset_m);
  store_le_u32(b + 20, m.pass_id);
  store_le_u64(b + 24, m.stamp_ns);
  store_le_u16(b + 32, m.keypoint_count);
  store_le_u16(b + 34, m.inliers);
  store_le_f32(b + 36, m.node_heading_rad);
  std::uint8_t* k = b + kExpRecordFixedBytes;
  for (const RouteKeypoint& kp : e.node.keypoints) {
    store_le_f32(k, kp.x_m);
    store_le_f32(k + 4, kp.y_m);
    store_le_f32(k + 8, kp.score);
    std::memcpy(k + 12, kp.descriptor, kDescriptorBytes);
    k += kKeypointBytes;
  }
  store_le_u32(b + n - 4, crc32(b, n - 4));
  return Status::ok();
}

// Decodes record `expected_record`; node (optional) receives the keypoints. out / node are written
// only when the whole record is valid.
inline Status decode_experience(const RouteParams& p, const ExperienceHeader& h, std::uint32_t node_count, Span<const std::uint8_t> in,
                                std::uint32_t expected_record, ExperienceMeta& out, RouteNode* node, ExperienceFormatCounters* c) noexcept {
  auto fail = [c](ExperienceFormatCounter e, StatusCode code, const char* why) {
    if (c != nullptr) c->increment(e);
    return Status(code, why);
  };
  const std::size_t n = exp_record_bytes(h.max_keypoints);
  if (in.size() < n) return fail(ExperienceFormatCounter::kShortBuffer, StatusCode::kTruncated, "experience record truncated");
  const std::uint8_t* b = in.data();
  if (std::memcmp(b, "QREX", 4) != 0) return fail(ExperienceFormatCounter::kBadRecordMagic, StatusCode::kCorrupt, "experience record bad magic");
  if (load_le_u32(b + n - 4) != crc32(b, n - 4))
    return fail(ExperienceFormatCounter::kBadRecordCrc, StatusCode::kCorrupt, "experience record CRC mismatch");
  ExperienceMeta m;
  m.record = load_le_u32(b + 4);
  m.node = load_le_u32(b + 8);
  m.slot = load_le_u16(b + 12);
  m.reverse = b[14] != 0;
  m.offset_m = load_le_f32(b + 16);
  m.pass_id = load_le_u32(b + 20);
  m.stamp_ns = load_le_u64(b + 24);
  m.keypoint_count = load_le_u16(b + 32);
  m.inliers = load_le_u16(b + 34);
  m.node_heading_rad = load_le_f32(b + 36);
  if (m.record != expected_record)
    return fail(ExperienceFormatCounter::kBadRecordIndex, StatusCode::kCorrupt, "experience record number out of sequence");
  const char* why = detail::experience_problem(p, h, node_count, m);
  const std::uint8_t* k = b + kExpRecordFixedBytes;
  for (std::size_t i = 0; why == nullptr && i < m.keypoint_count; ++i, k += kKeypointBytes)
    why = detail::keypoint_problem(p, load_le_f32(k), load_le_f32(k + 4), load_le_f32(k + 8));
  if (why != nullptr) return fail(ExperienceFormatCounter::kBadRecordField, StatusCode::kCorrupt, why);
  out = m;
  if (node != nullptr) {
    node->keypoints.clear();
    node->meta = NodeMeta{};
    node->meta.index = m.node;
    node->meta.pose.heading_rad = static_cast<double>(m.node_heading_rad);
    node->meta.stamp_ns = m.stamp_ns;
    node->meta.keypoint_count = m.keypoint_count;
    k = b + kExpRecordFixedBytes;
    for (std::size_t i = 0; i < m.keypoint_count; ++i, k += kKeypointBytes) {
      RouteKeypoint* kp = node->keypoints.emplace_back();
      kp->x_m = load_le_f32(k);
      kp->y_m = load_le_f32(k + 4);
      kp->score = load_le_f32(k + 8);
      std::memcpy(kp->descriptor, k + 12, kDescriptorBytes);
    }
  }
  return Status::ok();
}

// Gives a valid encoded record (decode_experience accepted it) a new record number, its CRC
// recomputed: compaction (drivers/route_store ExperienceFile) moves live records to the front.
inline Status renumber_experience(const ExperienceHeader& h, Span<std::uint8_t> rec, std::uint32_t record) noexcept {
  const std::size_t n = exp_record_bytes(h.max_keypoints);
  if (rec.size() < n) return Status(StatusCode::kCapacityExceeded, "experience record buffer too small");
  store_le_u32(rec.data() + 4, record);
  store_le_u32(rec.data() + n - 4, crc32(rec.data(), n - 4));
  return Status::ok();
}

// One slot of a node's experiences (record kNoExperience: empty).
struct ExperienceSlot {
  std::uint32_t record = kNoExperience;
  std::uint32_t pass_id = 0;
  float offset_m = 0.0f;
  bool reverse = false;
};

class ExperienceIndex {
 public:
  static std::size_t arena_bytes(std::size_t max_nodes, std::size_t per_node) noexcept {
    return max_nodes * per_node * sizeof(ExperienceSlot) + 64;
  }
  Status init(std::size_t max_nodes, std::size_t per_node, Arena& arena) noexcept {
    if (per_node == 0 || per_node > kMaxExperiencesPerNode) return Status(StatusCode::kInvalidArgument, "experience index: per_node outside 1..8");
    slots_ = arena.allocate<ExperienceSlot>(max_nodes * per_node);
    if (slots_.size() != max_nodes * per_node || max_nodes == 0) return Status(StatusCode::kCapacityExceeded, "experience index: arena too small");
    max_nodes_ = max_nodes;
    per_node_ = per_node;
    return reset(0);
  }
  // Forgets every experience; the route has node_count nodes (<= max_nodes).
  Status reset(std::size_t node_count) noexcept {
    if (node_count > max_nodes_) return Status(StatusCode::kCapacityExceeded, "experience index: route longer than max_nodes");
    for (ExperienceSlot& s : slots_) s = ExperienceSlot{};
    nodes_ = node_count;
    live_ = 0;
    return Status::ok();
  }
  // Records `m` in its (node, slot); an older record there is replaced, a newer one kept.
  Status set(const ExperienceMeta& m) noexcept {
    if (m.node >= nodes_ || m.slot >= per_node_) return Status(StatusCode::kOutOfRange, "experience index: node or slot out of range");
    ExperienceSlot& s = slots_[m.node * per_node_ + m.slot];
    if (s.record != kNoExperience && s.record > m.record) return Status::ok();
    if (s.record == kNoExperience) ++live_;
    s = ExperienceSlot{m.record, m.pass_id, m.offset_m, m.reverse};
    return Status::ok();
  }
  // The node's slots (empty ones have record kNoExperience); empty span for a node out of range.
  Span<const ExperienceSlot> slots(std::uint32_t node) const noexcept {
    if (node >= nodes_) return Span<const ExperienceSlot>();
    return Span<const ExperienceSlot>(slots_.data() + node * per_node_, per_node_);
  }
  // The slot a new experience of `node` goes to: the first empty one; when all are full, the oldest
  // (smallest record) other than `keep_record` (this pass's best match there); per_node_ when the
  // node is out of range.
  std::uint16_t choose_slot(std::uint32_t node, std::uint32_t keep_record) const noexcept {
    const Span<const ExperienceSlot> s = slots(node);
    if (s.empty()) return static_cast<std::uint16_t>(per_node_);
    std::size_t best = s.size();
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (s[i].record == kNoExperience) return static_cast<std::uint16_t>(i);
      if (s[i].record == keep_record && s.size() > 1) continue;
      if (best == s.size() || s[i].record < s[best].record) best = i;
    }
    return static_cast<std::uint16_t>(best == s.size() ? 0 : best);
  }
  std::size_t per_node() const noexcept { return per_node_; }
  std::size_t node_count() const noexcept { return nodes_; }
  std::size_t max_nodes() const noexcept { return max_nodes_; }
  std::size_t live() const noexcept { return live_; }

 private:
  Span<ExperienceSlot> slots_;
  std::size_t max_nodes_ = 0, per_node_ = 0, nodes_ = 0, live_ = 0;
};

}  // namespace qnav::route
