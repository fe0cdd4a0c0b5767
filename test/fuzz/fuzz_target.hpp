// The fuzz layer's one contract. Every fuzz_<name>.cpp defines
//   int qnav_fuzz_<name>(const std::uint8_t* data, std::size_t size)   // 0; never crash, hang, leak
//   void seeds_<name>(qnav::fuzz::Seeds& out)                            // starting inputs (may be empty)
// and registers them with QNAV_FUZZ_TARGET(name, mutations). The same object file is linked into
//  - test_fuzz_smoke (every build, every target incl. cross): each registered entry point runs over
//    its seeds, test/fuzz/regressions/<name>/* and `mutations` deterministic mutations of each seed;
//  - fuzz_<name> (QNAV_FUZZ=ON, clang): the libFuzzer binary (fuzz_main.cpp calls the one registered
//    target; its seeds are written into the corpus directory named by $QNAV_FUZZ_SEED_OUT at start).
// Seeds come from the real sample files (small excerpts cut at run time from QNAV_SHARED_DIR), files
// already in the repo (QNAV_SOURCE_DIR) and inputs encoded with the writers; nothing large is copied.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace qnav::fuzz {

using Entry = int (*)(const std::uint8_t* data, std::size_t size);

struct Seed {
  std::string name;   // file name in a corpus directory
  std::string bytes;
};
using Seeds = std::vector<Seed>;
using SeedFn = void (*)(Seeds& out);

struct Target {
  const char* name = "";
  Entry entry = nullptr;
  SeedFn seeds = nullptr;
  int mutations = 0;  // smoke test: deterministic mutations per seed (fewer for slow chain targets)
};

// Registration (static initialisers of the target objects); targets() in registration order.
bool register_target(const Target& t);
const std::vector<Target>& targets();

}  // namespace qnav::fuzz

#define QNAV_FUZZ_TARGET(name, mutations)                                                                          \
  [[maybe_unused]] static const bool qnav_fuzz_registered_##name =                                                 \
      ::qnav::fuzz::register_target(::qnav::fuzz::Target{#name, qnav_fuzz_##name, seeds_##name, mutations});
