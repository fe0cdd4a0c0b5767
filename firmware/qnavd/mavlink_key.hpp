// load_mavlink_key: the MAVLink 2 signing key (mavlink.key_file), checked and read once at start
// (Daemon::init), before any MAVLink traffic is read.
// The file must be:
//  - a regular file, named directly (a symbolic link is refused), owned by required_uid (production:
//    0 = root; the tests pass their own uid, hal::current_uid()), with no group or other permission
//    bits and no setuid/setgid/sticky bit (0600 or 0400);
//  - 64 hexadecimal digits (the 32-byte secret; upper or lower case), optionally followed by one line
//    end ("\n" or "\r\n") and nothing else, e.g. `openssl rand -hex 32`, or the SHA-256 of a
//    passphrase as MAVProxy and QGroundControl derive it: `printf %s PASSPHRASE | sha256sum | cut -c1-64`;
//  - not all zeros (ArduPilot reads an all-zero key as "signing off").
// Each refusal is a named error (StatusCode + "mavlink.key_file: ..." message) and start-up fails.
// The secret never appears in a log line or an error message. Reads through hal/linux (read_secret_file).
// O(1): at most 130 bytes read, no heap.
#pragma once

#include <cstdint>

#include "drivers/mavlink/frame.hpp"
#include "nav/core/status.hpp"

namespace qnav::daemon {

Result<drivers::mavlink::SigningKey> load_mavlink_key(const char* path, std::uint32_t required_uid) noexcept;

// The 32-byte secret from its text form (64 hex digits and at most one trailing line end).
Result<drivers::mavlink::SigningKey> parse_mavlink_key(const std::uint8_t* text, std::size_t n) noexcept;

}  // namespace qnav::daemon
