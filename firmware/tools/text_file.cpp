#include "firmware/tools/text_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace qnav::tools {

namespace {
Status read_bounded(const char* path, std::size_t max_bytes, bool text, std::string& out) {
  static char msg[600];
  out.clear();
  std::FILE* f = std::fopen(path, "rb");
  if (f == nullptr) {
    std::snprintf(msg, sizeof msg, "cannot open %s: %s", path, std::strerror(errno));
    return Status(StatusCode::kIoError, msg);
  }
  char buf[65536];
  std::size_t n;
  Status result = Status::ok();
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) {
    if (const void* z = text ? std::memchr(buf, '\0', n) : nullptr) {
      std::snprintf(msg, sizeof msg, "%s: NUL byte at offset %zu: binary data, not a text file", path,
                    out.size() + static_cast<std::size_t>(static_cast<const char*>(z) - buf));
      result = Status(StatusCode::kCorrupt, msg);
      break;
    }
    if (out.size() + n > max_bytes) {
      std::snprintf(msg, sizeof msg, "%s: larger than %zu MiB: split it", path, max_bytes >> 20);
      result = Status(StatusCode::kCapacityExceeded, msg);
      break;
    }
    out.append(buf, n);
  }
  if (result.is_ok() && std::ferror(f)) {
    std::snprintf(msg, sizeof msg, "cannot read %s: %s", path, std::strerror(errno));
    result = Status(StatusCode::kIoError, msg);
  }
  std::fclose(f);
  if (!result.is_ok()) out.clear();
  return result;
}
}  // namespace

Status read_text_file(const char* path, std::size_t max_bytes, std::string& out) { return read_bounded(path, max_bytes, true, out); }
Status read_binary_file(const char* path, std::size_t max_bytes, std::string& out) { return read_bounded(path, max_bytes, false, out); }

}  // namespace qnav::tools
