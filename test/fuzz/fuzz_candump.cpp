// candump log lines -> parse -> format -> parse again must give the same frame.
#include <cstring>

#include "hal/core/candump.hpp"
#include "test/fuzz/fuzz_support.hpp"


int qnav_fuzz_candump(const std::uint8_t* data, std::size_t size) {
  qnav::hal::CanLogRecord r;
  if (!qnav::hal::parse_can_log_line(reinterpret_cast<const char*>(data), size, r).is_ok()) return 0;
  char out[qnav::hal::kMaxCanLogLine];
  const std::size_t n = qnav::hal::format_can_log_line(r, out, sizeof out);
  qnav::hal::CanLogRecord r2;
  if (n == 0 || !qnav::hal::parse_can_log_line(out, n, r2).is_ok()) __builtin_trap();
  if (r2.frame.id != r.frame.id || r2.frame.len != r.frame.len || std::memcmp(r2.frame.data, r.frame.data, r.frame.len) != 0)
    __builtin_trap();
  return 0;
}

static void seeds_candump(qnav::fuzz::Seeds& out) {
  for (const char* s : {"(1436509052.249713) vcan0 123#DEADBEEF", "1F334455#1122334455667788", "123##1DEADBEEF", "123#R",
                        "(1.000000) can0 20000040#0000000000000000"})
    out.push_back(qnav::fuzz::Seed{"line" + std::to_string(out.size()), s});
}
QNAV_FUZZ_TARGET(candump, 500)
