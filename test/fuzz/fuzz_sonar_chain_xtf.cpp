// XTF bytes -> parsed pings -> ScanlineCorrector -> TileBuilder -> tile features (test/fuzz/sonar_chain.hpp).
#include "test/fuzz/sonar_chain.hpp"
#include "test/fuzz/sonar_seeds.hpp"

int qnav_fuzz_sonar_chain_xtf(const std::uint8_t* data, std::size_t size) { return qnav::fuzz::run_sonar_chain(data, size, false); }

static void seeds_sonar_chain_xtf(qnav::fuzz::Seeds& out) {
  qnav::fuzz::Seeds real;
  qnav::fuzz::add_real_xtf_seeds(real, 16);
  for (const qnav::fuzz::Seed& s : real) out.push_back(qnav::fuzz::Seed{s.name, std::string(1, '\0') + s.bytes});
  out.push_back(qnav::fuzz::Seed{"synthetic-24-pings-fix.xtf", std::string(1, '\0') + qnav::fuzz::synthetic_xtf(24, 96)});
  out.push_back(qnav::fuzz::Seed{"synthetic-24-pings-dr.xtf", std::string(1, '\1') + qnav::fuzz::synthetic_xtf(24, 96)});
}
QNAV_FUZZ_TARGET(sonar_chain_xtf, 6)
