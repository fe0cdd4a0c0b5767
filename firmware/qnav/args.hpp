// The older, lenient command-line helpers (`--name value` options, `--flag` switches, positional
// arguments; unknown options are NOT detected). Only `qnav map` still uses them: every other command
// declares its options on the strict parser (firmware/cli/cli_app.hpp, docs/cli.md). Delete this
// file when map moves too.
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>

namespace qnav::cli {

// Value of `--name VALUE`, or fallback when absent.
inline const char* option(int argc, char** argv, const char* name, const char* fallback = nullptr) noexcept {
  for (int i = 0; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], name) == 0) return argv[i + 1];
  return fallback;
}
inline bool flag(int argc, char** argv, const char* name) noexcept {
  for (int i = 0; i < argc; ++i)
    if (std::strcmp(argv[i], name) == 0) return true;
  return false;
}
// Parses a double option; returns false when present but not a number.
inline bool option_double(int argc, char** argv, const char* name, double& out) noexcept {
  const char* v = option(argc, argv, name);
  if (v == nullptr) return true;
  char* end = nullptr;
  errno = 0;
  const double d = std::strtod(v, &end);
  // Every numeric option is a finite number: "nan", "inf" and overflowing values are refused.
  if (end == v || *end != '\0' || errno == ERANGE || !std::isfinite(d)) return false;
  out = d;
  return true;
}
inline bool option_long(int argc, char** argv, const char* name, long& out) noexcept {
  const char* v = option(argc, argv, name);
  if (v == nullptr) return true;
  char* end = nullptr;
  errno = 0;
  const long l = std::strtol(v, &end, 10);
  if (end == v || *end != '\0' || errno == ERANGE) return false;
  out = l;
  return true;
}
// The i-th positional argument (not an option, not an option's value), counting from argv[first].
// `valued` lists the options that take a value, null-terminated.
inline const char* positional(int argc, char** argv, int first, int index, const char* const* valued) noexcept {
  int seen = 0;
  for (int i = first; i < argc; ++i) {
    if (std::strncmp(argv[i], "--", 2) == 0) {
      for (const char* const* v = valued; v != nullptr && *v != nullptr; ++v)
        if (std::strcmp(*v, argv[i]) == 0) {
          ++i;
          break;
        }
      continue;
    }
    if (seen++ == index) return argv[i];
  }
  return nullptr;
}

}  // namespace qnav::cli
