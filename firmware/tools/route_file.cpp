#include "firmware/tools/route_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace qnav::tools {

namespace {
Status write_all(int fd, const std::uint8_t* p, std::size_t n, off_t at) {
  while (n > 0) {
    const ssize_t w = ::pwrite(fd, p, n, at);
    if (w < 0) {
      if (errno == EINTR) continue;
      return Status(StatusCode::kIoError, "route file: write failed");
    }
    p += w;
    n -= static_cast<std::size_t>(w);
    at += w;
  }
  return Status::ok();
}
Status read_all(int fd, std::uint8_t* p, std::size_t n, off_t at) {
  while (n > 0) {
    const ssize_t r = ::pread(fd, p, n, at);
    if (r < 0) {
      if (errno == EINTR) continue;
      return Status(StatusCode::kIoError, "route file: read failed");
    }
    if (r == 0) return Status(StatusCode::kTruncated, "route file: unexpected end of file");
    p += r;
    n -= static_cast<std::size_t>(r);
    at += r;
  }
  return Status::ok();
}
// fsync the directory holding path, so a newly created file's name is durable too.
void sync_parent(const char* path) {
  char dir[4096];
  const char* slash = std::strrchr(path, '/');
  const std::size_t n = slash == nullptr ? 0 : static_cast<std::size_t>(slash - path);
  if (slash == nullptr) {
    std::strcpy(dir, ".");
  } else if (n == 0) {
    std::strcpy(dir, "/");
  } else {
    if (n >= sizeof dir) return;
    std::memcpy(dir, path, n);
    dir[n] = '\0';
  }
  const int d = ::open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (d >= 0) {
    static_cast<void>(::fsync(d));
    ::close(d);
  }
}
}  // namespace

RouteFileWriter::~RouteFileWriter() { close().ignore(); }

Status RouteFileWriter::create(const char* path, const route::RouteParams& params, const RouteWriterOptions& options) {
  if (fd_ >= 0) return Status(StatusCode::kInvalidArgument, "route writer: already open");
  std::uint8_t header[route::kHeaderBytes];
  QNAV_RETURN_IF_ERROR(route::encode_header(params, Span<std::uint8_t>(header)));
  const int flags = O_RDWR | O_CREAT | O_CLOEXEC | (options.overwrite ? O_TRUNC : O_EXCL);
  fd_ = ::open(path, flags, 0644);
  if (fd_ < 0) return Status(StatusCode::kIoError, errno == EEXIST ? "route writer: file exists" : "route writer: cannot create file");
  Status s = write_all(fd_, header, sizeof header, 0);
  if (s && ::fsync(fd_) != 0) s = Status(StatusCode::kIoError, "route writer: fsync failed");
  if (!s) {
    ::close(fd_);
    fd_ = -1;
    return s;
  }
  sync_parent(path);
  std::strncpy(path_, path, sizeof path_ - 1);
  params_ = params;
  options_ = options;
  count_ = 0;
  record_.assign(route::record_bytes(params.max_keypoints), 0);
  return Status::ok();
}

Status RouteFileWriter::open_append(const char* path, RouteAppendReport* report, const RouteWriterOptions& options) {
  if (fd_ >= 0) return Status(StatusCode::kInvalidArgument, "route writer: already open");
  fd_ = ::open(path, O_RDWR | O_CLOEXEC);
  if (fd_ < 0) return Status(StatusCode::kIoError, "route writer: cannot open file");
  auto fail = [this](Status s) {
    ::close(fd_);
    fd_ = -1;
    return s;
  };
  std::uint8_t header[route::kHeaderBytes];
  Status s = read_all(fd_, header, sizeof header, 0);
  if (!s) return fail(s);
  Result<route::RouteParams> p = route::decode_header(Span<const std::uint8_t>(header), nullptr);
  if (!p) return fail(p.status());
  struct stat st {};
  if (::fstat(fd_, &st) != 0) return fail(Status(StatusCode::kIoError, "route writer: stat failed"));
  const std::size_t rec = route::record_bytes(p->max_keypoints);
  const std::uint64_t body = static_cast<std::uint64_t>(st.st_size) - route::kHeaderBytes;
  const std::uint64_t n = body / rec;
  const std::uint64_t torn = body % rec;
  record_.assign(rec, 0);
  params_ = *p;
  options_ = options;
  if (n > 0) {
    s = read_all(fd_, record_.data(), rec, static_cast<off_t>(route::kHeaderBytes + (n - 1) * rec));
    route::NodeMeta m;
    if (s) s = route::decode_node_meta(params_, Span<const std::uint8_t>(record_.data(), rec), static_cast<std::uint32_t>(n - 1), m, nullptr);
    if (!s) return fail(s);  // a damaged last complete record: do not append after it
  }
  if (torn > 0) {
    if (::ftruncate(fd_, static_cast<off_t>(route::kHeaderBytes + n * rec)) != 0 || ::fsync(fd_) != 0)
      return fail(Status(StatusCode::kIoError, "route writer: cannot cut torn tail"));
  }
  count_ = static_cast<std::uint32_t>(n);
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
  const off_t at = static_cast<off_t>(route::kHeaderBytes + static_cast<std::uint64_t>(count_) * record_.size());
  QNAV_RETURN_IF_ERROR(write_all(fd_, record_.data(), record_.size(), at));
  if (options_.sync_each_node && ::fdatasync(fd_) != 0) return Status(StatusCode::kIoError, "route writer: fdatasync failed");
  ++count_;
  return Status::ok();
}

Status RouteFileWriter::close() {
  if (fd_ < 0) return Status::ok();
  Status s;
  if (::fsync(fd_) != 0) s = Status(StatusCode::kIoError, "route writer: fsync failed");
  if (::close(fd_) != 0 && s) s = Status(StatusCode::kIoError, "route writer: close failed");
  fd_ = -1;
  return s;
}

Status RouteFileWriter::commit_as(const char* final_path) {
  QNAV_RETURN_IF_ERROR(close());
  if (path_[0] == '\0') return Status(StatusCode::kNotReady, "route writer: nothing to commit");
  if (::rename(path_, final_path) != 0) return Status(StatusCode::kIoError, "route writer: rename to the final name failed");
  sync_parent(final_path);
  path_[0] = '\0';
  return Status::ok();
}

RouteFileReader::~RouteFileReader() { close(); }

void RouteFileReader::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  count_ = 0;
}

Status RouteFileReader::open(const char* path) {
  close();
  fd_ = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) return Status(StatusCode::kIoError, "route reader: cannot open file");
  std::uint8_t header[route::kHeaderBytes];
  struct stat st {};
  if (::fstat(fd_, &st) != 0) {
    close();
    return Status(StatusCode::kIoError, "route reader: stat failed");
  }
  if (static_cast<std::uint64_t>(st.st_size) < route::kHeaderBytes) {
    counters_.increment(route::RouteFormatCounter::kShortBuffer);
    close();
    return Status(StatusCode::kTruncated, "route file shorter than its header");
  }
  Status s = read_all(fd_, header, sizeof header, 0);
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
  const std::uint64_t body = static_cast<std::uint64_t>(st.st_size) - route::kHeaderBytes;
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
  return read_all(fd_, record_.data(), record_.size(), static_cast<off_t>(route::kHeaderBytes + static_cast<std::uint64_t>(index) * record_.size()));
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

}  // namespace qnav::tools
