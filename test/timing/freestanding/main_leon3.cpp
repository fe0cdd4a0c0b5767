// The freestanding LEON3 image: no OS, no glibc. Runs the workload (workload.hpp) and prints over the
// APBUART, one "key value" per line:
//   qnav-freestanding leon3
//   checksum vo_step <16 hex>
//   checksum route_update <16 hex>
//   checksum xtf_decode <16 hex>
//   checksum all <16 hex>
//   heap_used <bytes> heap_capacity <bytes>
//   status ok | status <message>
// then "EXIT <code>" (crt0/runtime) and powers off. run-checksum.sh compares the checksum lines with
// the host reference's (main_host.cpp).
#include "bare.hpp"
#include "test/timing/freestanding/workload.hpp"

namespace {
void line(const char* key, std::uint64_t v) {
  qnav::bare::put_str("checksum ");
  qnav::bare::put_str(key);
  qnav::bare::put_char(' ');
  qnav::bare::put_hex64(v);
  qnav::bare::put_str("\r\n");
}
}  // namespace

int main() {
  qnav::bare::put_str("qnav-freestanding leon3\r\n");
  qnav::timing::FreestandingResult r;
  const qnav::Status s = qnav::timing::run_freestanding_workload(r);
  line("vo_step", r.vo_step);
  line("route_update", r.route_update);
  line("xtf_decode", r.xtf_decode);
  line("all", r.all);
  for (int i = 0; i < qnav::timing::FreestandingResult::kStages; ++i) {
    qnav::bare::put_str("stage ");
    qnav::bare::put_str(r.stage_name[i]);
    qnav::bare::put_char(' ');
    qnav::bare::put_hex64(r.stage[i]);
    qnav::bare::put_str("\r\n");
  }
  qnav::bare::put_str("heap_used ");
  qnav::bare::put_u32(static_cast<std::uint32_t>(qnav::bare::heap_used()));
  qnav::bare::put_str(" heap_capacity ");
  qnav::bare::put_u32(static_cast<std::uint32_t>(qnav::bare::heap_capacity()));
  qnav::bare::put_str("\r\nstatus ");
  qnav::bare::put_str(s.is_ok() ? "ok" : s.message());
  qnav::bare::put_str("\r\n");
  return s.is_ok() ? 0 : 1;
}
