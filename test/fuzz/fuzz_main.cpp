// libFuzzer driver of one fuzz_<name> binary: exactly one target object is linked in (its static
// registration, test/fuzz/fuzz_target.hpp). At start-up the target's seeds are written into
// $QNAV_FUZZ_SEED_OUT (when set: the run's writable corpus directory), so libFuzzer starts from them.
#include <cstdio>
#include <cstdlib>

#include "test/fuzz/fuzz_support.hpp"

namespace {
const qnav::fuzz::Target& the_target() {
  const std::vector<qnav::fuzz::Target>& t = qnav::fuzz::targets();
  if (t.size() != 1) {
    std::fprintf(stderr, "fuzz_main: %zu targets linked, expected 1\n", t.size());
    std::abort();
  }
  return t[0];
}
}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const qnav::fuzz::Target& t = the_target();
  const char* out = std::getenv("QNAV_FUZZ_SEED_OUT");
  if (out == nullptr || *out == '\0' || t.seeds == nullptr) return 0;
  qnav::fuzz::Seeds seeds;
  t.seeds(seeds);
  for (const qnav::fuzz::Seed& s : seeds) {
    const std::string path = std::string(out) + "/seed-" + s.name;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) {
      std::fprintf(stderr, "fuzz_main: cannot write %s\n", path.c_str());
      std::abort();
    }
    std::fwrite(s.bytes.data(), 1, s.bytes.size(), f);
    std::fclose(f);
  }
  std::fprintf(stderr, "fuzz_main: %s: %zu seeds written to %s\n", t.name, seeds.size(), out);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const qnav::fuzz::Entry entry = the_target().entry;
  return entry(data, size);
}
