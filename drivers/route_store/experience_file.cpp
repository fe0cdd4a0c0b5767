#include "drivers/route_store/experience_file.hpp"
#include "drivers/route_store/store_io.hpp"

#include <cstdio>
#include <cstring>

namespace qnav::drivers::route_store {

bool experience_path(const char* route_path, char (&out)[kExperiencePathBytes]) noexcept {
  const int n = std::snprintf(out, sizeof out, "%s.exp", route_path);
  return n > 0 && n < static_cast<int>(sizeof out);
}

Status route_identity(const route::RouteParams& params, route::NodeSource& nodes, route::RouteNode& scratch, Span<std::uint8_t> scratch_bytes,
                      RouteIdentity& out) {
  if (nodes.node_count() == 0) return Status(StatusCode::kInvalidArgument, "route identity: the route has no node");
  if (scratch_bytes.size() < route::record_bytes(params.max_keypoints)) return Status(StatusCode::kCapacityExceeded, "route identity: scratch too small");
  QNAV_RETURN_IF_ERROR(nodes.load(0, scratch));
  out.params = params;
  out.node_count = nodes.node_count();
  return route::route_binding(params, scratch, scratch_bytes, out.header_crc, out.node0_crc);
}

ExperienceFile::~ExperienceFile() { close(); }

void ExperienceFile::close() {
  if (fd_ >= 0) {
    store_.sync(fd_).ignore();
    store_.close(fd_);
  }
  fd_ = -1;
  records_ = 0;
}

Status ExperienceFile::open_common(const char* path, const RouteIdentity& route, route::ExperienceIndex& index, ExperienceOpenReport* report,
                                   bool write, std::uint64_t& file_size) {
  other_route_ = false;
  std::uint64_t size = 0;
  QNAV_RETURN_IF_ERROR(open_sized(store_, path, write ? hal::FileMode::kReadWrite : hal::FileMode::kRead, fd_, size));
  auto fail = [this](Status s) {
    store_.close(fd_);
    fd_ = -1;
    return s;
  };
  file_size = size;
  std::uint8_t hb[route::kExpHeaderBytes];
  if (size < route::kExpHeaderBytes) {
    counters_.increment(route::ExperienceFormatCounter::kShortBuffer);
    return fail(Status(StatusCode::kTruncated, "experience file shorter than its header"));
  }
  const Status hs = store_.read_at(fd_, hb, sizeof hb, 0);
  if (!hs) return fail(hs);
  Result<route::ExperienceHeader> hd = route::decode_exp_header(Span<const std::uint8_t>(hb), &counters_);
  if (!hd) return fail(hd.status());
  if (hd->route_header_crc != route.header_crc || hd->route_node0_crc != route.node0_crc) {
    counters_.increment(route::ExperienceFormatCounter::kOtherRoute);
    other_route_ = true;
    return fail(Status(StatusCode::kInvalidArgument, "experience file belongs to another route (taught again since?)"));
  }
  if (hd->max_keypoints != route.params.max_keypoints) {
    counters_.increment(route::ExperienceFormatCounter::kBadHeader);
    return fail(Status(StatusCode::kCorrupt, "experience file: max_keypoints differs from the route's"));
  }
  if (hd->max_per_node > index.per_node())
    return fail(Status(StatusCode::kInvalidArgument, "experience file holds more experiences per node than configured (route.max_experiences)"));
  header_ = *hd;
  params_ = route.params;
  route_nodes_ = route.node_count;
  const std::size_t rec = route::exp_record_bytes(header_.max_keypoints);
  record_.assign(rec, 0);
  const std::uint64_t body = size - route::kExpHeaderBytes;
  if (body / rec > 0xFFFFFFF0ull) return fail(Status(StatusCode::kUnsupported, "experience file: too many records"));
  records_ = static_cast<std::uint32_t>(body / rec);
  const Status rs = index.reset(route.node_count);
  if (!rs) return fail(rs);
  ExperienceOpenReport r;
  r.records = records_;
  r.torn_bytes = body % rec;
  if (r.torn_bytes > 0) counters_.increment(route::ExperienceFormatCounter::kTornTail);
  for (std::uint32_t i = 0; i < records_; ++i) {
    route::ExperienceMeta m;
    const Status ms = load_meta(i, m);
    if (!ms) {
      if (r.damaged++ == 0) r.first_damaged = i;
      continue;
    }
    if (m.slot >= index.per_node()) {  // cannot be: checked against the header's max_per_node
      ++r.damaged;
      continue;
    }
    index.set(m).ignore();
  }
  r.live = static_cast<std::uint32_t>(index.live());
  if (report != nullptr) {
    const bool created = report->created, moved = report->moved_stale;
    *report = r;
    report->created = created;
    report->moved_stale = moved;
  }
  return Status::ok();
}

Status ExperienceFile::open_read(const char* path, const RouteIdentity& route, route::ExperienceIndex& index, ExperienceOpenReport* report) {
  close();
  if (report != nullptr) *report = ExperienceOpenReport{};
  std::uint64_t size = 0;
  return open_common(path, route, index, report, false, size);
}

Status ExperienceFile::open_append(const char* path, const RouteIdentity& route, std::uint16_t per_node, route::ExperienceIndex& index,
                                   ExperienceOpenReport* report, bool sync_each) {
  close();
  if (report != nullptr) *report = ExperienceOpenReport{};
  sync_each_ = sync_each;
  if (per_node == 0 || per_node > index.per_node())
    return Status(StatusCode::kInvalidArgument, "experience file: per_node must be 1..the index's per_node");
  route::ExperienceHeader want;
  want.max_keypoints = route.params.max_keypoints;
  want.max_per_node = per_node;
  want.route_header_crc = route.header_crc;
  want.route_node0_crc = route.node0_crc;
  std::uint8_t hb[route::kExpHeaderBytes];
  QNAV_RETURN_IF_ERROR(route::encode_exp_header(want, Span<std::uint8_t>(hb)));
  auto create = [&](hal::FileMode mode) -> Status {
    Result<int> h = store_.open(path, mode);
    if (!h) return h.status();
    Status s = store_.write_at(*h, hb, sizeof hb, 0);
    if (s) s = store_.sync(*h);
    store_.close(*h);
    if (s) s = store_.sync_name(path);
    if (s && report != nullptr) report->created = true;
    return s;
  };
  Result<int> probe = store_.open(path, hal::FileMode::kRead);
  if (!probe) {
    if (probe.status().code() != StatusCode::kNotFound) return probe.status();
    QNAV_RETURN_IF_ERROR(create(hal::FileMode::kCreateNew));
  } else {
    Result<std::uint64_t> sz = store_.size(*probe);
    store_.close(*probe);
    if (!sz) return sz.status();
    // Shorter than its header: a power cut while it was created (no record can be in it).
    if (*sz < route::kExpHeaderBytes) QNAV_RETURN_IF_ERROR(create(hal::FileMode::kCreateOrTruncate));
  }
  std::uint64_t size = 0;
  Status s = open_common(path, route, index, report, true, size);
  if (!s && other_route_) {
    // Another teach's experiences: kept aside (never deleted), a new companion for this route.
    char stale[kExperiencePathBytes + 8];
    if (std::snprintf(stale, sizeof stale, "%s.stale", path) >= static_cast<int>(sizeof stale))
      return Status(StatusCode::kInvalidArgument, "experience file: path too long");
    QNAV_RETURN_IF_ERROR(store_.rename(path, stale));
    QNAV_RETURN_IF_ERROR(create(hal::FileMode::kCreateNew));
    if (report != nullptr) report->moved_stale = true;
    s = open_common(path, route, index, report, true, size);
  }
  QNAV_RETURN_IF_ERROR(s);
  const std::uint64_t end = route::kExpHeaderBytes + static_cast<std::uint64_t>(records_) * record_.size();
  if (size > end) {  // a torn tail: cut before anything is appended
    s = store_.truncate(fd_, end);
    if (s) s = store_.sync(fd_);
    if (!s) {
      close();
      return s;
    }
  }
  const std::uint32_t live = static_cast<std::uint32_t>(index.live());
  const std::uint32_t dead = records_ - live;
  if (dead > 0 && dead >= live && dead >= compact_min_dead_) {
    ExperienceOpenReport local;
    ExperienceOpenReport& r = report != nullptr ? *report : local;
    const Status cs = compact(path, route, index, r);
    if (!cs) {
      if (fd_ < 0) return cs;  // neither file could be opened again
      r.compact_failed = true;
      r.compact_status = cs;
    }
  }
  return Status::ok();
}

Status ExperienceFile::compact(const char* path, const RouteIdentity& route, route::ExperienceIndex& index, ExperienceOpenReport& report) {
  char tmp[kExperiencePathBytes + 8];
  if (std::snprintf(tmp, sizeof tmp, "%s.new", path) >= static_cast<int>(sizeof tmp))
    return Status(StatusCode::kInvalidArgument, "experience file: path too long");
  Result<int> h = store_.open(tmp, hal::FileMode::kCreateOrTruncate);
  if (!h) return h.status();
  const int out = *h;
  std::uint8_t hb[route::kExpHeaderBytes];
  Status s = store_.read_at(fd_, hb, sizeof hb, 0);
  if (s) s = store_.write_at(out, hb, sizeof hb, 0);
  std::uint32_t kept = 0;
  const Span<std::uint8_t> rec(record_.data(), record_.size());
  for (std::uint32_t i = 0; s && i < records_; ++i) {
    route::ExperienceMeta m;
    if (!read_record(i)) continue;
    if (!route::decode_experience(params_, header_, route_nodes_, Span<const std::uint8_t>(rec.data(), rec.size()), i, m, nullptr, nullptr))
      continue;  // damaged: dropped (it was never in the index)
    const Span<const route::ExperienceSlot> slots = index.slots(m.node);
    if (m.slot >= slots.size() || slots[m.slot].record != i) continue;  // replaced by a later record
    s = route::renumber_experience(header_, rec, kept);
    if (s) s = store_.write_at(out, rec.data(), rec.size(), route::kExpHeaderBytes + static_cast<std::uint64_t>(kept) * rec.size());
    ++kept;
  }
  if (s) s = store_.sync(out);
  store_.close(out);
  if (!s) return s;  // ROUTE.exp untouched and still open
  const std::uint32_t before = records_;
  const std::uint64_t torn = report.torn_bytes;
  store_.close(fd_);
  fd_ = -1;
  records_ = 0;
  const Status rs = store_.rename(tmp, path);  // atomic: the old file or the compacted one
  std::uint64_t size = 0;
  const Status os = open_common(path, route, index, &report, true, size);  // keeps created / moved_stale
  report.torn_bytes = torn;
  if (!os) return os;
  if (!rs) return rs;
  report.compacted = true;
  report.dropped = before - records_;
  return Status::ok();
}

Status ExperienceFile::append(route::Experience& e, route::ExperienceIndex& index) {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "experience file: not open");
  e.meta.record = records_;
  QNAV_RETURN_IF_ERROR(route::encode_experience(params_, header_, route_nodes_, e, Span<std::uint8_t>(record_.data(), record_.size())));
  const std::uint64_t at = route::kExpHeaderBytes + static_cast<std::uint64_t>(records_) * record_.size();
  Status s = store_.write_at(fd_, record_.data(), record_.size(), at);
  if (s && sync_each_) s = store_.sync_data(fd_);
  if (!s) {
    store_.truncate(fd_, at).ignore();  // a partial record is cut (a reader would ignore it as a torn tail)
    return s;
  }
  ++records_;
  e.meta.keypoint_count = static_cast<std::uint16_t>(e.node.keypoints.size());
  return index.set(e.meta);
}

Status ExperienceFile::read_record(std::uint32_t record) noexcept {
  return read_fixed_record(store_, fd_, Span<std::uint8_t>(record_.data(), record_.size()), route::kExpHeaderBytes, record, records_,
                           "experience file: not open", "experience file: record beyond the file");
}

Status ExperienceFile::load(std::uint32_t record, route::RouteNode& out) noexcept {
  QNAV_RETURN_IF_ERROR(read_record(record));
  route::ExperienceMeta m;
  return route::decode_experience(params_, header_, route_nodes_, Span<const std::uint8_t>(record_.data(), record_.size()), record, m, &out,
                                  &counters_);
}

Status ExperienceFile::load_meta(std::uint32_t record, route::ExperienceMeta& out) noexcept {
  QNAV_RETURN_IF_ERROR(read_record(record));
  return route::decode_experience(params_, header_, route_nodes_, Span<const std::uint8_t>(record_.data(), record_.size()), record, out, nullptr,
                                  &counters_);
}

}  // namespace qnav::drivers::route_store
