// JSF bytes -> framed, paired pings -> ScanlineCorrector -> TileBuilder -> tile features (test/fuzz/sonar_chain.hpp).
#include "test/fuzz/sonar_chain.hpp"
#include "test/fuzz/sonar_seeds.hpp"

int qnav_fuzz_sonar_chain_jsf(const std::uint8_t* data, std::size_t size) { return qnav::fuzz::run_sonar_chain(data, size, true); }

static void seeds_sonar_chain_jsf(qnav::fuzz::Seeds& out) {
  out.push_back(qnav::fuzz::Seed{"synthetic-24-pings-fix.jsf", std::string(1, '\0') + qnav::fuzz::synthetic_jsf(24, 96)});
  out.push_back(qnav::fuzz::Seed{"synthetic-24-pings-dr.jsf", std::string(1, '\1') + qnav::fuzz::synthetic_jsf(24, 96)});
}
QNAV_FUZZ_TARGET(sonar_chain_jsf, 6)
