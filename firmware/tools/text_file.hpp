// Reads a whole text file (a candump log, a DBC) for the qnav tool, bounded: a file larger than
// max_bytes, or one holding a NUL byte (binary data, /dev/zero), is refused with a clear message
// before it can exhaust memory. Errors name the file and carry the OS reason.
#pragma once

#include <cstddef>
#include <string>

#include "nav/core/status.hpp"

namespace qnav::tools {

// Status messages point into a per-call static buffer (valid until the next call).
Status read_text_file(const char* path, std::size_t max_bytes, std::string& out);
// The same for binary data (a JSF recording): bounded, NUL bytes allowed.
Status read_binary_file(const char* path, std::size_t max_bytes, std::string& out);

}  // namespace qnav::tools
