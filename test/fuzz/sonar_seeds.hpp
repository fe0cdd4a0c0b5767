// Side-scan seeds for the XTF/JSF targets: the first pings of the real XTF files in ../shared/data
// (cut at packet boundaries at run time; nothing is copied into the repo) and small files encoded with
// the drivers' own writers (there is no real JSF sample). Header-only: several target objects use it.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "drivers/sidescan/jsf_parser.hpp"
#include "drivers/sidescan/xtf_parser.hpp"
#include "drivers/sidescan/xtf_writer.hpp"
#include "test/fuzz/fuzz_support.hpp"

namespace qnav::fuzz {

// The file header and the packets of a real XTF file up to (and including) its `pings`-th sonar packet.
inline std::string xtf_excerpt(const std::string& path, int pings) {
  const std::string all = read_prefix(path, 1u << 20);
  const auto* b = reinterpret_cast<const std::uint8_t*>(all.data());
  Result<sidescan::XtfFileHeader> h = sidescan::parse_xtf_file_header(Span<const std::uint8_t>(b, all.size()));
  if (!h) return {};
  std::size_t off = h->header_bytes;
  int seen = 0;
  while (off < all.size() && seen < pings) {
    Result<sidescan::XtfPacketHeader> p = sidescan::parse_xtf_packet_header(Span<const std::uint8_t>(b + off, all.size() - off));
    if (!p || p->num_bytes == 0 || off + p->num_bytes > all.size()) break;
    if (p->header_type == 0) ++seen;
    off += p->num_bytes;
  }
  return all.substr(0, off);
}

inline void add_real_xtf_seeds(Seeds& out, int pings) {
  const std::string d = shared_dir() + "/data/sidescan/";
  const std::string iver = xtf_excerpt(d + "cidco-scotsman-iver2/scotsman-iver2.xtf", pings);
  if (!iver.empty()) out.push_back(Seed{"iver2-first-" + std::to_string(pings) + "-pings.xtf", iver});
  // Multibeam-only XTF: packets the reader must skip (first 32 KiB).
  const std::string mb = read_prefix(d + "cidco-r2sonic-multibeam-xtf/0009-150708_R2Testing-0001.xtf", 32u << 10);
  if (!mb.empty()) out.push_back(Seed{"r2sonic-first-32k.xtf", mb});
}

// A short synthetic survey line: ping k at 0.3 m steps heading 30 deg, a bright target every 9 samples.
inline void synthetic_samples(int k, int n, std::vector<float>& s) {
  s.assign(static_cast<std::size_t>(n), 0.0f);
  for (int i = 0; i < n; ++i)
    s[static_cast<std::size_t>(i)] = (i < n / 8 ? 2.0f : 40.0f + 20.0f * std::sin(0.7f * static_cast<float>(i + 3 * k))) + ((i + k) % 9 == 0 ? 60.0f : 0.0f);
}

inline std::string synthetic_xtf(int pings, int samples) {
  std::string out(sidescan::kXtfFileHeaderBytes, '\0');
  auto* b = reinterpret_cast<std::uint8_t*>(&out[0]);
  if (!sidescan::encode_xtf_file_header(Span<std::uint8_t>(b, out.size()), 3, "FUZZ")) return {};
  std::vector<float> port, stbd;
  std::string pkt(sidescan::xtf_ping_bytes(static_cast<std::size_t>(samples)), '\0');
  for (int k = 0; k < pings; ++k) {
    synthetic_samples(k, samples, port);
    synthetic_samples(k + 5, samples, stbd);
    sidescan::XtfWritePing w;
    w.stamp_ns = 1436509052000000000ull + static_cast<std::uint64_t>(k) * 200000000ull;
    w.ping_number = static_cast<std::uint32_t>(k);
    w.sensor_y = 46.8 + 2.3e-6 * k;
    w.sensor_x = -71.2 + 2.0e-6 * k;
    w.heading_deg = 30.0f;
    w.speed_knots = 2.9f;
    w.altitude_m = 6.0f;
    w.slant_range_m = 30.0f;
    w.port = Span<const float>(port.data(), port.size());
    w.stbd = Span<const float>(stbd.data(), stbd.size());
    Result<std::size_t> n = sidescan::encode_xtf_ping(Span<std::uint8_t>(reinterpret_cast<std::uint8_t*>(&pkt[0]), pkt.size()), w);
    if (!n) return {};
    out.append(pkt.data(), n.value());
  }
  return out;
}

inline std::string synthetic_jsf(int pings, int samples) {
  std::string out;
  std::vector<float> s;
  std::string msg(sidescan::jsf_sonar_message_bytes(static_cast<std::size_t>(samples)), '\0');
  for (int k = 0; k < pings; ++k)
    for (std::uint8_t ch = 0; ch < 2; ++ch) {
      synthetic_samples(k + 5 * ch, samples, s);
      sidescan::JsfWriteSonar w;
      w.channel = ch;
      w.ping_number = static_cast<std::uint32_t>(k);
      w.stamp_ns = 1436509052000000000ull + static_cast<std::uint64_t>(k) * 200000000ull;
      w.sample_interval_ns = static_cast<std::uint32_t>(40000000 / samples);  // 30 m slant range at 1500 m/s
      w.altitude_m = 6.0f;
      w.heading_deg = 30.0f;
      w.lat_deg = 46.8 + 2.3e-6 * k;
      w.lon_deg = -71.2 + 2.0e-6 * k;
      w.samples = Span<const float>(s.data(), s.size());
      Result<std::size_t> n = sidescan::encode_jsf_sonar_message(Span<std::uint8_t>(reinterpret_cast<std::uint8_t*>(&msg[0]), msg.size()), w);
      if (!n) return {};
      out.append(msg.data(), n.value());
    }
  return out;
}

}  // namespace qnav::fuzz
