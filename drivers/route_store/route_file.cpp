#include "drivers/route_store/route_file.hpp"
#include "drivers/route_store/store_io.hpp"

#include <cstdio>
#include <cstring>

namespace qnav::drivers::route_store {

namespace {

// What follows the last complete record of a route file.
struct Tail {
  std::uint64_t nodes = 0;       // complete records
  std::uint64_t bytes = 0;       // bytes after them
  bool end_mark = false;         // those bytes are a valid end mark
  std::uint32_t mark_nodes = 0;  // ... recording this many nodes
  bool bad_mark = false;         // they look like an end mark (magic) but are damaged
};

Status read_tail(hal::FileStore& store, int fd, std::uint64_t file_size, std::size_t rec, Tail& t) noexcept {
  const std::uint64_t body = file_size - route::kHeaderBytes;
  t = Tail{};
  t.nodes = body / rec;
  t.bytes = body % rec;
  if (t.bytes != route::kEndMarkBytes) return Status::ok();
  std::uint8_t mark[route::kEndMarkBytes];
  QNAV_RETURN_IF_ERROR(store.read_at(fd, mark, sizeof mark, route::kHeaderBytes + t.nodes * rec));
  Result<std::uint32_t> n = route::decode_end_mark(Span<const std::uint8_t>(mark), nullptr);
  if (n) {
    t.end_mark = true;
    t.mark_nodes = *n;
  } else {
    t.bad_mark = std::memcmp(mark, "QEND", 4) == 0;
  }
  return Status::ok();
}

bool copy_path(char (&dst)[kRoutePathBytes], const char* src) noexcept {
  if (std::strlen(src) >= kRoutePathBytes) return false;
  std::strncpy(dst, src, kRoutePathBytes - 1);
  dst[kRoutePathBytes - 1] = '\0';
  return true;
}

}  // namespace

const char* to_string(RouteEnd e) noexcept {
  switch (e) {
    case RouteEnd::kClosedCleanly: return "closed cleanly";
    case RouteEnd::kCutOff: return "cut off: no end mark (the writer was killed or lost power before closing the route)";
    case RouteEnd::kCountMismatch: return "cut off: the end mark's node count disagrees with the records";
    case RouteEnd::kNoEndMarkV1: return "no end marker: version 1 (complete or cut off cannot be told)";
  }
  return "unknown";
}

RouteFileWriter::~RouteFileWriter() { abandon().ignore(); }

Status RouteFileWriter::create(const char* path, const route::RouteParams& params, const RouteWriterOptions& options) {
  if (fd_ >= 0) return Status(StatusCode::kInvalidArgument, "route writer: already open");
  std::uint8_t header[route::kHeaderBytes];
  QNAV_RETURN_IF_ERROR(route::encode_header(params, Span<std::uint8_t>(header)));
  if (std::strlen(path) >= sizeof path_) return Status(StatusCode::kInvalidArgument, "route writer: path too long");
  Result<int> h = store_.open(path, hal::FileMode::kCreateNew);  // never truncates a route
  if (!h) return h.status();
  fd_ = *h;
  Status s = store_.write_at(fd_, header, sizeof header, 0);
  if (s) s = store_.sync(fd_);
  if (s) s = store_.sync_name(path);
  if (!s) {
    store_.close(fd_);
    fd_ = -1;
    return s;
  }
  copy_path(path_, path);
  final_path_[0] = '\0';
  params_ = params;
  options_ = options;
  count_ = 0;
  write_failed_ = false;
  record_.assign(route::record_bytes(params.max_keypoints), 0);
  return Status::ok();
}

Status RouteFileWriter::create_replacement(const char* final_path, const route::RouteParams& params, const RouteWriterOptions& options,
                                           RouteReplaceReport* report) {
  if (fd_ >= 0) return Status(StatusCode::kInvalidArgument, "route writer: already open");
  char temp[kRoutePathBytes], kept[kRoutePathBytes], final_copy[kRoutePathBytes];
  if (!copy_path(final_copy, final_path) || std::snprintf(temp, sizeof temp, "%s.new", final_path) >= static_cast<int>(sizeof temp) ||
      std::snprintf(kept, sizeof kept, "%s.new.kept.999", final_path) >= static_cast<int>(sizeof kept))
    return Status(StatusCode::kInvalidArgument, "route writer: path too long");
  QNAV_RETURN_IF_ERROR(route::validate_params(params));
  if (!options.replace_existing) {
    Result<int> probe = store_.open(final_path, hal::FileMode::kRead);
    if (probe) {
      store_.close(*probe);
      return Status(StatusCode::kInvalidArgument, "route exists");  // replaced only when the caller says so
    }
    if (probe.status().code() != StatusCode::kNotFound) return probe.status();
  }
  if (report != nullptr) *report = RouteReplaceReport{};
  // A teach run that was cut off left its nodes under .new: move them aside, never delete them.
  Status moved(StatusCode::kNotFound, "");
  for (int n = 1; n < 1000; ++n) {
    std::snprintf(kept, sizeof kept, "%s.new.kept.%d", final_path, n);
    Result<int> probe = store_.open(kept, hal::FileMode::kRead);
    if (probe) {
      store_.close(*probe);
      continue;
    }
    moved = store_.rename(temp, kept);
    break;
  }
  if (!moved && moved.code() != StatusCode::kNotFound) return moved;
  if (moved && report != nullptr) {
    report->previous_kept = true;
    copy_path(report->kept_path, kept);
  }
  QNAV_RETURN_IF_ERROR(create(temp, params, options));
  copy_path(final_path_, final_copy);
  if (report != nullptr) copy_path(report->temp_path, temp);
  return Status::ok();
}

Status RouteFileWriter::open_append(const char* path, RouteAppendReport* report, const RouteWriterOptions& options) {
  if (fd_ >= 0) return Status(StatusCode::kInvalidArgument, "route writer: already open");
  if (std::strlen(path) >= sizeof path_) return Status(StatusCode::kInvalidArgument, "route writer: path too long");
  if (report != nullptr) *report = RouteAppendReport{};
  std::uint64_t size = 0;
  QNAV_RETURN_IF_ERROR(open_sized(store_, path, hal::FileMode::kReadWrite, fd_, size));
  auto fail = [this](Status s) {
    store_.close(fd_);
    fd_ = -1;
    return s;
  };
  std::uint8_t header[route::kHeaderBytes];
  if (size < route::kHeaderBytes) return fail(Status(StatusCode::kTruncated, "route file shorter than its header"));
  Status s = store_.read_at(fd_, header, sizeof header, 0);
  if (!s) return fail(s);
  route::RouteHeaderInfo info;
  Result<route::RouteParams> p = route::decode_header(Span<const std::uint8_t>(header), nullptr, &info);
  if (!p) return fail(p.status());
  const std::size_t rec = route::record_bytes(p->max_keypoints);
  Tail tail;
  s = read_tail(store_, fd_, size, rec, tail);
  if (!s) return fail(s);
  if (tail.nodes > 0xFFFFFFFEull) return fail(Status(StatusCode::kUnsupported, "route writer: too many nodes"));
  const std::uint64_t n = tail.nodes;
  record_.assign(rec, 0);
  params_ = *p;
  options_ = options;
  if (report != nullptr) {
    report->nodes = static_cast<std::uint32_t>(n);
    report->version = info.version;
  }
  if (n > 0) {
    s = store_.read_at(fd_, record_.data(), rec, route::kHeaderBytes + (n - 1) * rec);
    route::NodeMeta m;
    if (s) {
      s = route::decode_node_meta(params_, Span<const std::uint8_t>(record_.data(), rec), static_cast<std::uint32_t>(n - 1), m, nullptr);
      if (!s && report != nullptr) report->damaged = true;
    }
    if (!s) return fail(s);  // a damaged last complete record: do not append after it
  }
  const bool mark = tail.end_mark && tail.mark_nodes == n;
  if (tail.bytes > 0) {  // a torn tail or the end mark: the route is open for appending from here
    s = store_.truncate(fd_, route::kHeaderBytes + n * rec);
    if (s) s = store_.sync(fd_);
    if (!s) return fail(s);
  }
  count_ = static_cast<std::uint32_t>(n);
  write_failed_ = false;
  copy_path(path_, path);
  final_path_[0] = '\0';
  if (report != nullptr) {
    report->torn_bytes = mark ? 0 : tail.bytes;
    report->end_mark_cut = mark;
  }
  return Status::ok();
}

Status RouteFileWriter::append(const route::RouteNode& node) {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "route writer: not open");
  const route::RouteNode* n = &node;
  route::RouteNode tmp;
  if (node.meta.index != count_) {  // the record's index is its position in the file
    tmp = node;
    tmp.meta.index = count_;
    n = &tmp;
  }
  QNAV_RETURN_IF_ERROR(route::encode_node(params_, *n, Span<std::uint8_t>(record_.data(), record_.size())));
  const std::uint64_t at = route::kHeaderBytes + static_cast<std::uint64_t>(count_) * record_.size();
  Status s = store_.write_at(fd_, record_.data(), record_.size(), at);
  if (s && options_.sync_each_node) s = store_.sync_data(fd_);
  if (!s) {
    write_failed_ = true;  // part of the record may be on the medium: close() cuts it
    return s;
  }
  ++count_;
  return Status::ok();
}

Status RouteFileWriter::finish(bool mark) {
  if (fd_ < 0) return Status::ok();
  const std::uint64_t end = route::kHeaderBytes + static_cast<std::uint64_t>(count_) * record_.size();
  Status s;
  if (write_failed_) s = store_.truncate(fd_, end);
  if (s && mark) {
    std::uint8_t m[route::kEndMarkBytes];
    s = route::encode_end_mark(count_, Span<std::uint8_t>(m));
    if (s) s = store_.write_at(fd_, m, sizeof m, end);
  }
  const Status ss = store_.sync(fd_);
  store_.close(fd_);
  fd_ = -1;
  return s ? ss : s;
}

Status RouteFileWriter::close() { return finish(true); }

Status RouteFileWriter::abandon() { return finish(false); }

Status RouteFileWriter::commit_as(const char* final_path) {
  if (fd_ < 0 && path_[0] == '\0') return Status(StatusCode::kNotReady, "route writer: nothing to commit");
  QNAV_RETURN_IF_ERROR(close());
  if (path_[0] == '\0') return Status(StatusCode::kNotReady, "route writer: nothing to commit");
  QNAV_RETURN_IF_ERROR(store_.rename(path_, final_path));
  path_[0] = '\0';
  final_path_[0] = '\0';
  return Status::ok();
}

Status RouteFileWriter::commit() {
  if (final_path_[0] == '\0') return Status(StatusCode::kNotReady, "route writer: not created by create_replacement");
  char final_copy[kRoutePathBytes];
  copy_path(final_copy, final_path_);
  return commit_as(final_copy);
}

RouteFileReader::~RouteFileReader() { close(); }

void RouteFileReader::close() {
  if (fd_ >= 0) store_.close(fd_);
  fd_ = -1;
  count_ = 0;
  file_nodes_ = 0;
  torn_bytes_ = 0;
  version_ = 0;
  end_ = RouteEnd::kCutOff;
  end_mark_nodes_ = 0;
}

Status RouteFileReader::open(const char* path) {
  close();
  std::uint64_t size = 0;
  QNAV_RETURN_IF_ERROR(open_sized(store_, path, hal::FileMode::kRead, fd_, size));
  auto fail = [this](Status s) {
    close();
    return s;
  };
  std::uint8_t header[route::kHeaderBytes];
  if (size < route::kHeaderBytes) {
    counters_.increment(route::RouteFormatCounter::kShortBuffer);
    return fail(Status(StatusCode::kTruncated, "route file shorter than its header"));
  }
  Status s = store_.read_at(fd_, header, sizeof header, 0);
  if (!s) return fail(s);
  route::RouteHeaderInfo info;
  Result<route::RouteParams> p = route::decode_header(Span<const std::uint8_t>(header), &counters_, &info);
  if (!p) return fail(p.status());
  params_ = *p;
  const std::size_t rec = route::record_bytes(params_.max_keypoints);
  Tail tail;
  s = read_tail(store_, fd_, size, rec, tail);
  if (!s) return fail(s);
  if (tail.nodes > 0xFFFFFFFEull) return fail(Status(StatusCode::kUnsupported, "route reader: too many nodes"));
  file_nodes_ = count_ = static_cast<std::uint32_t>(tail.nodes);
  version_ = info.version;
  if (tail.end_mark) {
    end_mark_nodes_ = tail.mark_nodes;
    end_ = tail.mark_nodes == tail.nodes ? RouteEnd::kClosedCleanly : RouteEnd::kCountMismatch;
    if (end_ == RouteEnd::kCountMismatch) counters_.increment(route::RouteFormatCounter::kBadEndMark);
  } else {
    torn_bytes_ = tail.bytes;
    end_ = version_ < 2 ? RouteEnd::kNoEndMarkV1 : RouteEnd::kCutOff;
    if (tail.bad_mark) counters_.increment(route::RouteFormatCounter::kBadEndMark);
    if (torn_bytes_ > 0) counters_.increment(route::RouteFormatCounter::kTornTail);
    counters_.increment(route::RouteFormatCounter::kNoEndMark);
  }
  record_.assign(rec, 0);
  return Status::ok();
}

Status RouteFileReader::limit_nodes(std::uint32_t n) noexcept {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "route reader: not open");
  if (n > file_nodes_) return Status(StatusCode::kOutOfRange, "route reader: more nodes than the file holds");
  count_ = n;
  return Status::ok();
}

Status RouteFileReader::read_record(std::uint32_t index) noexcept {
  return read_fixed_record(store_, fd_, Span<std::uint8_t>(record_.data(), record_.size()), route::kHeaderBytes, index, count_,
                           "route reader: not open", "route reader: node index beyond the route");
}

Status RouteFileReader::load(std::uint32_t index, route::RouteNode& out) noexcept {
  QNAV_RETURN_IF_ERROR(read_record(index));
  return route::decode_node(params_, Span<const std::uint8_t>(record_.data(), record_.size()), index, out, &counters_);
}

Status RouteFileReader::load_meta(std::uint32_t index, route::NodeMeta& out) noexcept {
  QNAV_RETURN_IF_ERROR(read_record(index));
  return route::decode_node_meta(params_, Span<const std::uint8_t>(record_.data(), record_.size()), index, out, &counters_);
}

Status RouteFileReader::read_all_meta(std::vector<route::NodeMeta>& out, std::uint32_t* first_bad) {
  out.clear();
  out.reserve(count_);
  for (std::uint32_t i = 0; i < count_; ++i) {
    route::NodeMeta m;
    const Status s = load_meta(i, m);
    if (!s) {
      if (first_bad != nullptr) *first_bad = i;
      return s;
    }
    out.push_back(m);
  }
  if (first_bad != nullptr) *first_bad = count_;
  return Status::ok();
}

}  // namespace qnav::drivers::route_store
