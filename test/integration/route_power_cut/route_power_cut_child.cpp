// The teaching process the power-cut test kills: teaches a synthetic route through the route store
// (drivers/route_store on the host's file system, the code qnavd and `qnav route train` use) as fast
// as the disk allows, the way the tool does: under FINAL.new, committed over FINAL when complete.
//   route_power_cut_child FINAL NODES SEED [--replace]
// stdout, one line each, flushed before the next step:
//   start | kept PATH (a previous run's FINAL.new moved aside) | created | durable I (append(I)
//   returned: node I is on the medium) | committed N
// Exit 0 when committed, 1 on an error (reported on stderr).
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "firmware/tools/route_file.hpp"
#include "test/integration/route_power_cut/synthetic_nodes.hpp"

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s FINAL NODES SEED [--replace]\n", argv[0]);
    return 2;
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  const char* final_path = argv[1];
  const long nodes = std::strtol(argv[2], nullptr, 10);
  const unsigned long seed = std::strtoul(argv[3], nullptr, 10);
  const bool replace = argc > 4 && std::strcmp(argv[4], "--replace") == 0;
  std::printf("start\n");
  qnav::tools::RouteFileWriter w;
  qnav::tools::RouteWriterOptions o;
  o.replace_existing = replace;
  qnav::tools::RouteReplaceReport rep;
  qnav::Status s = w.create_replacement(final_path, qnav::test::power_cut_params(), o, &rep);
  if (!s) {
    std::fprintf(stderr, "create: %s\n", s.message());
    return 1;
  }
  if (rep.previous_kept) std::printf("kept %s\n", rep.kept_path);
  std::printf("created\n");
  for (long i = 0; i < nodes; ++i) {
    s = w.append(qnav::test::power_cut_node(seed, static_cast<std::uint32_t>(i)));
    if (!s) {
      std::fprintf(stderr, "append %ld: %s\n", i, s.message());
      return 1;
    }
    std::printf("durable %ld\n", i);
  }
  s = w.commit();
  if (!s) {
    std::fprintf(stderr, "commit: %s\n", s.message());
    return 1;
  }
  std::printf("committed %ld\n", nodes);
  return 0;
}
