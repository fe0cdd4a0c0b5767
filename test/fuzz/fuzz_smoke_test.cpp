// Runs every registered fuzz entry point (test/fuzz/fuzz_target.hpp) over its seeds, every stored
// crash input in test/fuzz/regressions/<name>/ and a fixed set of deterministic mutations of each
// seed, in every build and on every target (the leon3 run included). A crash, trap or sanitizer report
// fails the test; the real fuzzing is the libFuzzer build (scripts/fuzz, ctest -L fuzz in host-clang).
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "test/fuzz/fuzz_support.hpp"

namespace {
using qnav::fuzz::Target;

std::uint32_t next(std::uint32_t& s) {
  s ^= s << 13;
  s ^= s >> 17;
  s ^= s << 5;
  return s;
}

void call(const Target& t, const std::string& x) { t.entry(reinterpret_cast<const std::uint8_t*>(x.data()), x.size()); }

std::string mutate(const std::string& s, std::uint32_t& rng) {
  std::string x = s;
  const int edits = 1 + static_cast<int>(next(rng) % 4);
  for (int k = 0; k < edits && !x.empty(); ++k) {
    const std::size_t pos = next(rng) % x.size();
    switch (next(rng) % 6) {
      case 0: x[pos] = static_cast<char>(x[pos] ^ (1u << (next(rng) % 8))); break;
      case 1: x.erase(pos, 1 + next(rng) % 4); break;
      case 2: x.insert(pos, 1, static_cast<char>(next(rng) & 0xFF)); break;
      case 3: x.resize(pos); break;
      case 4: {  // an extreme byte or 32-bit value
        static const std::uint32_t kValues[] = {0u, 0xFFu, 0x7Fu, 0x80u, 0xFFFFFFFFu, 0x7FFFFFFFu, 0x80000000u, 0x7F800000u};
        const std::uint32_t v = kValues[next(rng) % 8];
        for (std::size_t b = 0; b < 4 && pos + b < x.size(); ++b) x[pos + b] = static_cast<char>((v >> (8 * b)) & 0xFF);
        break;
      }
      default: x.insert(pos, x.substr(0, next(rng) % (x.size() + 1))); break;
    }
  }
  return x;
}

class FuzzSmoke : public ::testing::TestWithParam<Target> {};

TEST_P(FuzzSmoke, SeedsRegressionsAndMutations) {
  const Target& t = GetParam();
  qnav::fuzz::Seeds seeds;
  if (t.seeds != nullptr) t.seeds(seeds);
  // Stored crash inputs: replayed as they are (they are the regression tests of the fixes).
  const std::string dir = qnav::fuzz::source_dir() + "/test/fuzz/regressions/" + t.name;
  for (const std::string& f : qnav::fuzz::list_files(dir)) {
    SCOPED_TRACE(f);
    call(t, qnav::fuzz::read_prefix(f, 16u << 20));
  }
  std::uint32_t rng = 0x9E3779B9u;
  for (const qnav::fuzz::Seed& s : seeds) {
    SCOPED_TRACE(s.name);
    call(t, s.bytes);
    for (int m = 0; m < t.mutations; ++m) call(t, mutate(s.bytes, rng));
  }
  call(t, std::string());
  RecordProperty("seeds", static_cast<int>(seeds.size()));
}

std::string target_name(const ::testing::TestParamInfo<Target>& info) { return info.param.name; }

INSTANTIATE_TEST_SUITE_P(All, FuzzSmoke, ::testing::ValuesIn(qnav::fuzz::targets()), target_name);

TEST(FuzzSmokeRegistry, EveryTargetHasSeeds) {
  ASSERT_FALSE(qnav::fuzz::targets().empty());
  for (const Target& t : qnav::fuzz::targets()) {
    qnav::fuzz::Seeds s;
    if (t.seeds != nullptr) t.seeds(s);
    EXPECT_FALSE(s.empty()) << t.name;
  }
}
}  // namespace
