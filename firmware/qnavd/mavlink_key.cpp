#include "firmware/qnavd/mavlink_key.hpp"

#include "hal/linux/secret_file.hpp"

namespace qnav::daemon {
namespace {
int hex_digit(std::uint8_t c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}
}  // namespace

Result<drivers::mavlink::SigningKey> parse_mavlink_key(const std::uint8_t* text, std::size_t n) noexcept {
  if (n > 0 && text[n - 1] == '\n') --n;
  if (n > 0 && text[n - 1] == '\r') --n;
  if (n != 64)
    return Status(StatusCode::kCorrupt, "mavlink.key_file: not a 32-byte key (must hold exactly 64 hex digits and at most one line end; "
                                        "e.g. openssl rand -hex 32)");
  drivers::mavlink::SigningKey k;
  std::uint8_t any = 0;
  for (std::size_t i = 0; i < 32; ++i) {
    const int hi = hex_digit(text[2 * i]), lo = hex_digit(text[2 * i + 1]);
    if (hi < 0 || lo < 0) return Status(StatusCode::kCorrupt, "mavlink.key_file: a character that is not a hex digit");
    k.secret[i] = static_cast<std::uint8_t>(hi << 4 | lo);
    any = static_cast<std::uint8_t>(any | k.secret[i]);
  }
  if (any == 0) return Status(StatusCode::kInvalidArgument, "mavlink.key_file: an all-zero key (ArduPilot reads it as signing off)");
  return k;
}

Result<drivers::mavlink::SigningKey> load_mavlink_key(const char* path, std::uint32_t required_uid) noexcept {
  std::uint8_t text[66];  // 64 digits + "\r\n"; one byte more tells a longer file (truncated)
  Result<hal::SecretFileInfo> r = hal::read_secret_file(path, Span<std::uint8_t>(text, sizeof text));
  if (!r) return r.status();
  const hal::SecretFileInfo& f = r.value();
  if (!f.regular) return Status(StatusCode::kInvalidArgument, "mavlink.key_file: not a regular file");
  if (f.owner_uid != required_uid)
    return Status(StatusCode::kInvalidArgument, "mavlink.key_file: not owned by root (chown root:root FILE)");
  if ((f.mode & 07077) != 0)
    return Status(StatusCode::kInvalidArgument, "mavlink.key_file: group or others have access, or a setuid/setgid/sticky bit (chmod 600 FILE)");
  if (f.truncated)
    return Status(StatusCode::kCorrupt, "mavlink.key_file: not a 32-byte key (longer than 64 hex digits and a line end)");
  return parse_mavlink_key(text, f.bytes);
}

}  // namespace qnav::daemon
