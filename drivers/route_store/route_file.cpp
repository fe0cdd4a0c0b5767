#include "drivers/route_store/route_file.hpp"

#include <cstring>

namespace qnav::drivers::route_store {


RouteFileWriter::~RouteFileWriter() { close().ignore(); }

Status RouteFileWriter::create(const char* path, const route::RouteParams& params, const RouteWriterOptions& options) {
  if (fd_ >= 0) return Status(StatusCode::kInvalidArgument, "route writer: already open");
  std::uint8_t header[route::kHeaderBytes];
  QNAV_RETURN_IF_ERROR(route::encode_header(params, Span<std::uint8_t>(header)));
  if (std::strlen(path) >= sizeof path_) return Status(StatusCode::kInvalidArgument, "route writer: path too long");
  Result<int> h = store_.open(path, options.overwrite ? hal::FileMode::kCreateOrTruncate : hal::FileMode::kCreateNew);
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
  std::strncpy(path_, path, sizeof path_ - 1);
  params_ = params;
  options_ = options;
  count_ = 0;
  record_.assign(route::record_bytes(params.max_keypoints), 0);
  return Status::ok();
}

Status RouteFileWriter::open_append(const char* path, RouteAppendReport* report, const RouteWriterOptions& options) {
  if (fd_ >= 0) return Status(StatusCode::kInvalidArgument, "route writer: already open");
  if (std::strlen(path) >= sizeof path_) return Status(StatusCode::kInvalidArgument, "route writer: path too long");
  Result<int> h = store_.open(path, hal::FileMode::kReadWrite);
  if (!h) return h.status();
  fd_ = *h;
  auto fail = [this](Status s) {
    store_.close(fd_);
    fd_ = -1;
    return s;
  };
  std::uint8_t header[route::kHeaderBytes];
  Status s = store_.read_at(fd_, header, sizeof header, 0);
  if (!s) return fail(s);
  Result<route::RouteParams> p = route::decode_header(Span<const std::uint8_t>(header), nullptr);
  if (!p) return fail(p.status());
  Result<std::uint64_t> size = store_.size(fd_);
  if (!size) return fail(size.status());
  const std::size_t rec = route::record_bytes(p->max_keypoints);
  const std::uint64_t body = *size - route::kHeaderBytes;
  const std::uint64_t n = body / rec;
  const std::uint64_t torn = body % rec;
  record_.assign(rec, 0);
  params_ = *p;
  options_ = options;
  if (n > 0) {
    s = store_.read_at(fd_, record_.data(), rec, route::kHeaderBytes + (n - 1) * rec);
    route::NodeMeta m;
    if (s) s = route::decode_node_meta(params_, Span<const std::uint8_t>(record_.data(), rec), static_cast<std::uint32_t>(n - 1), m, nullptr);
    if (!s) return fail(s);  // a damaged last complete record: do not append after it
  }
  if (torn > 0) {
    s = store_.truncate(fd_, route::kHeaderBytes + n * rec);
    if (s) s = store_.sync(fd_);
    if (!s) return fail(s);
  }
  count_ = static_cast<std::uint32_t>(n);
  std::strncpy(path_, path, sizeof path_ - 1);
  if (report != nullptr) {
    report->nodes = count_;
    report->torn_bytes = torn;
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
  QNAV_RETURN_IF_ERROR(store_.write_at(fd_, record_.data(), record_.size(), at));
  if (options_.sync_each_node) QNAV_RETURN_IF_ERROR(store_.sync_data(fd_));
  ++count_;
  return Status::ok();
}

Status RouteFileWriter::close() {
  if (fd_ < 0) return Status::ok();
  const Status s = store_.sync(fd_);
  store_.close(fd_);
  fd_ = -1;
  return s;
}

Status RouteFileWriter::commit_as(const char* final_path) {
  QNAV_RETURN_IF_ERROR(close());
  if (path_[0] == '\0') return Status(StatusCode::kNotReady, "route writer: nothing to commit");
  QNAV_RETURN_IF_ERROR(store_.rename(path_, final_path));
  path_[0] = '\0';
  return Status::ok();
}

RouteFileReader::~RouteFileReader() { close(); }

void RouteFileReader::close() {
  if (fd_ >= 0) store_.close(fd_);
  fd_ = -1;
  count_ = 0;
}

Status RouteFileReader::open(const char* path) {
  close();
  Result<int> h = store_.open(path, hal::FileMode::kRead);
  if (!h) return h.status();
  fd_ = *h;
  std::uint8_t header[route::kHeaderBytes];
  Result<std::uint64_t> size = store_.size(fd_);
  if (!size) {
    const Status e = size.status();
    close();
    return e;
  }
  if (*size < route::kHeaderBytes) {
    counters_.increment(route::RouteFormatCounter::kShortBuffer);
    close();
    return Status(StatusCode::kTruncated, "route file shorter than its header");
  }
  Status s = store_.read_at(fd_, header, sizeof header, 0);
  if (!s) {
    close();
    return s;
  }
  Result<route::RouteParams> p = route::decode_header(Span<const std::uint8_t>(header), &counters_);
  if (!p) {
    close();
    return p.status();
  }
  params_ = *p;
  const std::size_t rec = route::record_bytes(params_.max_keypoints);
  const std::uint64_t body = *size - route::kHeaderBytes;
  if (body / rec > 0xFFFFFFFEull) {
    close();
    return Status(StatusCode::kUnsupported, "route reader: too many nodes");
  }
  count_ = static_cast<std::uint32_t>(body / rec);
  torn_bytes_ = body % rec;
  record_.assign(rec, 0);
  return Status::ok();
}

Status RouteFileReader::read_record(std::uint32_t index) noexcept {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "route reader: not open");
  if (index >= count_) return Status(StatusCode::kOutOfRange, "route reader: node index beyond the route");
  return store_.read_at(fd_, record_.data(), record_.size(), route::kHeaderBytes + static_cast<std::uint64_t>(index) * record_.size());
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
