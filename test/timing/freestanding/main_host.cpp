// Host reference of the freestanding LEON3 image: the same workload (workload.hpp), compiled from
// the same sources with the host compiler and linked against the same newlib libm, printing the same
// checksum lines as main_leon3.cpp.
#include <cinttypes>
#include <cstdio>

#include "test/timing/freestanding/workload.hpp"

int main() {
  qnav::timing::FreestandingResult r;
  const qnav::Status s = qnav::timing::run_freestanding_workload(r);
  std::printf("qnav-freestanding host\n");
  std::printf("checksum vo_step %016" PRIx64 "\n", r.vo_step);
  std::printf("checksum route_update %016" PRIx64 "\n", r.route_update);
  std::printf("checksum xtf_decode %016" PRIx64 "\n", r.xtf_decode);
  std::printf("checksum all %016" PRIx64 "\n", r.all);
  for (int i = 0; i < qnav::timing::FreestandingResult::kStages; ++i)
    std::printf("stage %s %016" PRIx64 "\n", r.stage_name[i], r.stage[i]);
  std::printf("status %s\n", s.is_ok() ? "ok" : s.message());
  return s.is_ok() ? 0 : 1;
}
