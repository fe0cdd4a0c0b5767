#include "nav/route/route_format.hpp"

#include <cmath>
#include <cstring>

#include "nav/core/byte_order.hpp"
#include "nav/core/crc.hpp"

namespace qnav::route {

namespace {
constexpr std::uint8_t kHeaderMagic[8] = {'Q', 'N', 'A', 'V', 'R', 'T', 'E', 0};
constexpr std::uint8_t kRecordMagic[4] = {'Q', 'R', 'N', 'D'};

void count(RouteFormatCounters* c, RouteFormatCounter e) noexcept {
  if (c != nullptr) c->increment(e);
}
bool finite_positive(float v) noexcept { return std::isfinite(v) && v > 0.0f; }
}  // namespace

const char* to_string(SensorKind k) noexcept {
  switch (k) {
    case SensorKind::kSideScan: return "sidescan";
    case SensorKind::kCamera: return "camera";
    case SensorKind::kUnknown: break;
  }
  return "unknown";
}

Status validate_params(const RouteParams& p) noexcept {
  if (p.sensor != SensorKind::kSideScan && p.sensor != SensorKind::kCamera)
    return Status(StatusCode::kInvalidArgument, "route sensor kind must be sidescan or camera");
  if (p.max_keypoints == 0 || p.max_keypoints > kMaxKeypointsPerNode)
    return Status(StatusCode::kInvalidArgument, "route max_keypoints outside 1..kMaxKeypointsPerNode");
  if (p.descriptor_bytes != kDescriptorBytes) return Status(StatusCode::kUnsupported, "route descriptor size unsupported");
  if (!finite_positive(p.node_spacing_m) || !finite_positive(p.tile_length_m) || !finite_positive(p.tile_width_m) ||
      !finite_positive(p.pixel_m))
    return Status(StatusCode::kInvalidArgument, "route lengths must be finite and positive");
  if (!std::isfinite(p.depth_m) || p.depth_m < 0.0f) return Status(StatusCode::kInvalidArgument, "route depth must be finite, >= 0");
  return Status::ok();
}

Status encode_header(const RouteParams& p, Span<std::uint8_t> out) noexcept {
  QNAV_RETURN_IF_ERROR(validate_params(p));
  if (out.size() < kHeaderBytes) return Status(StatusCode::kCapacityExceeded, "header buffer too small");
  std::uint8_t* b = out.data();
  std::memset(b, 0, kHeaderBytes);
  std::memcpy(b, kHeaderMagic, 8);
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

Result<RouteParams> decode_header(Span<const std::uint8_t> in, RouteFormatCounters* counters) noexcept {
  if (in.size() < kHeaderBytes) {
    count(counters, RouteFormatCounter::kShortBuffer);
    return Status(StatusCode::kTruncated, "route file shorter than its header");
  }
  const std::uint8_t* b = in.data();
  if (std::memcmp(b, kHeaderMagic, 8) != 0) {
    count(counters, RouteFormatCounter::kBadHeaderMagic);
    return Status(StatusCode::kCorrupt, "not a qnav route file (bad magic)");
  }
  if (load_le_u32(b + 60) != crc32(b, 60)) {
    count(counters, RouteFormatCounter::kBadHeaderCrc);
    return Status(StatusCode::kCorrupt, "route header CRC mismatch");
  }
  if (load_le_u16(b + 8) != kRouteFormatVersion || load_le_u16(b + 10) != kHeaderBytes) {
    count(counters, RouteFormatCounter::kUnsupportedVersion);
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
    count(counters, RouteFormatCounter::kBadParams);
    return s;
  }
  return p;
}

Status encode_node(const RouteParams& p, const RouteNode& node, Span<std::uint8_t> out) noexcept {
  const std::size_t n = record_bytes(p.max_keypoints);
  if (p.max_keypoints == 0 || p.max_keypoints > kMaxKeypointsPerNode)
    return Status(StatusCode::kInvalidArgument, "route max_keypoints outside 1..kMaxKeypointsPerNode");
  if (out.size() < n) return Status(StatusCode::kCapacityExceeded, "record buffer too small");
  if (node.keypoints.size() > p.max_keypoints) return Status(StatusCode::kCapacityExceeded, "node has more keypoints than the route allows");
  if (!node.meta.pose.is_finite() || !std::isfinite(node.meta.along_m))
    return Status(StatusCode::kInvalidArgument, "node pose not finite");
  std::uint8_t* b = out.data();
  std::memset(b, 0, n);
  std::memcpy(b, kRecordMagic, 4);
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

namespace {
Status check_record(const RouteParams& p, Span<const std::uint8_t> in, std::uint32_t expected_index, NodeMeta& meta,
                    RouteFormatCounters* counters) noexcept {
  const std::size_t n = record_bytes(p.max_keypoints);
  if (in.size() < n) {
    count(counters, RouteFormatCounter::kShortBuffer);
    return Status(StatusCode::kTruncated, "route record truncated");
  }
  const std::uint8_t* b = in.data();
  if (std::memcmp(b, kRecordMagic, 4) != 0) {
    count(counters, RouteFormatCounter::kBadRecordMagic);
    return Status(StatusCode::kCorrupt, "route record bad magic");
  }
  if (load_le_u32(b + n - 4) != crc32(b, n - 4)) {
    count(counters, RouteFormatCounter::kBadRecordCrc);
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
    count(counters, RouteFormatCounter::kBadRecordIndex);
    return Status(StatusCode::kCorrupt, "route record index out of sequence");
  }
  if (m.keypoint_count > p.max_keypoints || !m.pose.is_finite() || !std::isfinite(m.along_m)) {
    count(counters, RouteFormatCounter::kBadRecordField);
    return Status(StatusCode::kCorrupt, "route record field out of range");
  }
  meta = m;
  return Status::ok();
}
}  // namespace

Status decode_node_meta(const RouteParams& p, Span<const std::uint8_t> in, std::uint32_t expected_index,
                        NodeMeta& out, RouteFormatCounters* counters) noexcept {
  return check_record(p, in, expected_index, out, counters);
}

Status decode_node(const RouteParams& p, Span<const std::uint8_t> in, std::uint32_t expected_index, RouteNode& out,
                   RouteFormatCounters* counters) noexcept {
  NodeMeta meta;
  QNAV_RETURN_IF_ERROR(check_record(p, in, expected_index, meta, counters));
  const std::uint8_t* k = in.data() + kRecordFixedBytes;
  for (std::size_t i = 0; i < meta.keypoint_count; ++i, k += kKeypointBytes) {
    if (!std::isfinite(load_le_f32(k)) || !std::isfinite(load_le_f32(k + 4)) || !std::isfinite(load_le_f32(k + 8))) {
      count(counters, RouteFormatCounter::kBadRecordField);
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
