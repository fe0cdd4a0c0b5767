// qnavd's configuration (TOML, firmware/qnavd/config): any text through parse_config. It must accept
// or refuse with an error naming the key and line; an accepted configuration must hold the bounds
// the daemon sizes its buffers from (queues powers of two, mission within its fixed capacity).
#include <cstddef>
#include <cstdint>
#include <string>

#include "firmware/qnavd/config.hpp"
#include "test/fuzz/fuzz_support.hpp"

namespace {
bool power_of_two(std::size_t v) { return v != 0 && (v & (v - 1)) == 0; }
}  // namespace

int qnav_fuzz_config(const std::uint8_t* data, std::size_t size) {
  using namespace qnav::daemon;
  const std::string text(reinterpret_cast<const char*>(data), size);
  DaemonConfig c;
  ConfigError err;
  if (!parse_config(text, "fuzz.toml", c, err)) {
    if (err.to_string().empty()) __builtin_trap();
    return 0;
  }
  if (!power_of_two(c.ping_queue) || !power_of_two(c.can_rx_queue) || !power_of_two(c.can_tx_queue) ||
      c.max_samples_per_side < 64 || c.max_samples_per_side > 16384 || c.max_nodes < 2)
    __builtin_trap();
  return 0;
}

static void seeds_config(qnav::fuzz::Seeds& out) {
  const std::string src = qnav::fuzz::source_dir();
  qnav::fuzz::add_file_seed(out, "sim.toml", src + "/firmware/qnavd/config/sim.toml");
  qnav::fuzz::add_file_seed(out, "vehicle.toml", src + "/firmware/qnavd/config/vehicle.toml");
  // The unit test's configuration with every key set (between kEveryKey = R"( and )").
  const std::string t = qnav::fuzz::read_prefix(src + "/test/unit/firmware/qnavd_config/config_test.cpp", 1u << 20);
  const std::size_t a = t.find("kEveryKey = R\"(");
  const std::size_t b = a == std::string::npos ? a : t.find(")\"", a);
  if (b != std::string::npos) out.push_back(qnav::fuzz::Seed{"every-key.toml", t.substr(a + 15, b - a - 15)});
  out.push_back(qnav::fuzz::Seed{"recorded-pass.toml",
                                 "[daemon]\nbackend = \"sim\"\n[sim]\nreplay_lines = 40\n[[sim.pass]]\nmode = \"teach\"\n"
                                 "file = \"x.xtf\"\nfirst_ping = 1\nlast_ping = -1\n"});
}
QNAV_FUZZ_TARGET(config, 100)
