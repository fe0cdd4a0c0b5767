// qnav version: build facts an engineer needs when reporting a result.
#include <cstdio>

#include "firmware/cli/cli_app.hpp"
#include "firmware/qnav/command.hpp"
#include "nav/core/byte_order.hpp"

namespace {
int run_version() {
  std::printf("qnav %s (%s, %s-endian, %zu-bit, C++%ld)\n", QNAV_VERSION, QNAV_BUILD_TYPE,
              qnav::host_is_big_endian() ? "big" : "little", sizeof(void*) * 8, __cplusplus / 100 % 100 + 0L);
  return 0;
}
void setup_version(CLI::App& cmd, qnav::cli::Runner& run) { run.on(&cmd, run_version); }
}  // namespace

QNAV_CLI_COMMAND("version", "print version and build facts", setup_version);
