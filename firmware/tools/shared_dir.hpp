// Where the sample data (../shared/data: sonar, stereo, downward camera recordings) is found, for the
// qnav tool, the tests and the benchmarks. One lookup, in this order:
//   1. $QNAV_SHARED_DIR, when set and it holds data/;
//   2. the checkout's ../shared compiled in by CMake (-DQNAV_SHARED_DIR=..., the presets set it);
// and when neither holds data/, the first of them (so a missing file names where it was looked for)
// with shared_dir_missing() saying both places and the fix. Header-only, no state: getenv + stat.
#pragma once

#include <sys/stat.h>

#include <cstdlib>
#include <string>

namespace qnav::tools {

#ifdef QNAV_SHARED_DIR
inline constexpr const char* kCompiledSharedDir = QNAV_SHARED_DIR;
#else
inline constexpr const char* kCompiledSharedDir = "../shared";
#endif

// True when DIR/data is a directory.
inline bool holds_shared_data(const std::string& dir) {
  struct stat st {};
  return !dir.empty() && ::stat((dir + "/data").c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

// The shared folder (the one holding data/), without a trailing slash.
inline std::string shared_dir() {
  const char* env = std::getenv("QNAV_SHARED_DIR");
  const std::string from_env = env ? env : "";
  if (holds_shared_data(from_env)) return from_env;
  if (holds_shared_data(kCompiledSharedDir)) return kCompiledSharedDir;
  return from_env.empty() ? std::string(kCompiledSharedDir) : from_env;
}

// Empty when the sample data is there; otherwise one line naming both places looked in and the fix.
inline std::string shared_dir_missing() {
  if (holds_shared_data(shared_dir())) return {};
  const char* env = std::getenv("QNAV_SHARED_DIR");
  return std::string("sample data not found: no data/ in $QNAV_SHARED_DIR (") + (env ? env : "unset") +
         ") nor in the build's " + kCompiledSharedDir +
         "; set QNAV_SHARED_DIR to the folder that holds data/ (README.md)";
}

}  // namespace qnav::tools
