// qnav xtf info FILE: what an XTF file holds (header, channels, pings, time span, navigation,
// packet types skipped, reader counters). Reads the whole file once with the fixed-buffer reader.
#include <cinttypes>
#include <cstdio>
#include <cerrno>
#include <cstring>
#include <string>
#include <vector>

#include "drivers/sidescan/xtf_reader.hpp"
#include "firmware/cli/cli_app.hpp"
#include "firmware/qnav/command.hpp"
#include "firmware/tools/file_source.hpp"

namespace {

using namespace qnav;
using namespace qnav::sidescan;
using qnav::tools::FileSource;

const char* channel_type(std::uint8_t t) {
  switch (t) {
    case 0: return "subbottom";
    case 1: return "port";
    case 2: return "starboard";
    case 3: return "bathymetry";
    default: return "other";
  }
}

int xtf_info(const char* path) {
  if (const std::string e = qnav::cli::input_file_problem(path); !e.empty()) {
    std::fprintf(stderr, "qnav xtf info: %s\n", e.c_str());
    return 1;
  }
  FileSource src;
  if (!src.open(path)) {
    std::fprintf(stderr, "qnav xtf info: cannot open %s: %s\n", path, std::strerror(errno));
    return 1;
  }
  XtfReader reader;
  if (!reader.init(XtfReaderConfig{})) return 1;
  const Status o = reader.open(src);
  if (!o) {
    std::fprintf(stderr, "qnav xtf info: %s: %s\n", path, o.message());
    return 1;
  }
  const XtfFileHeader& h = reader.header();
  std::printf("file          %s\n", path);
  std::printf("recorded by   %s %s, system type %u, sonar \"%s\" (type %u)\n", h.recording_program, h.recording_version,
              h.system_type, h.sonar_name, h.sonar_type);
  std::printf("nav units     %u (%s)\n", h.nav_units, h.nav_units == 3 ? "lat/lon degrees" : "metres");
  std::printf("channels      %u sonar, %u bathymetry\n", h.num_sonar_channels, h.num_bathy_channels);
  for (std::size_t i = 0; i < h.channels.size(); ++i) {
    const XtfChannelInfo& c = h.channels[i];
    std::printf("  [%zu] %-10s %-9s %u bytes/sample %s, %.0f kHz\n", i, c.name, channel_type(c.type_of_channel),
                c.bytes_per_sample, c.unipolar ? "unipolar" : "bipolar", static_cast<double>(c.frequency_khz));
  }
  std::vector<float> port(65536), stbd(65536);
  XtfRecord rec;
  std::uint64_t pings = 0, with_nav = 0, attitude = 0, navigation = 0;
  std::uint64_t first_ns = 0, last_ns = 0;
  std::uint32_t samples = 0;
  float range_m = 0.0f, alt_min = 1e9f, alt_max = -1e9f;
  int rc = 0;
  for (;;) {
    const Result<bool> r = reader.next(rec, Span<float>(port.data(), port.size()), Span<float>(stbd.data(), stbd.size()));
    if (!r) {
      std::fprintf(stderr, "qnav xtf info: %s: %s at byte %" PRIu64 "\n", path, r.status().message(), reader.bytes_read());
      rc = 1;
      continue;
    }
    if (!r.value()) break;
    if (rec.kind == XtfRecordKind::kPing) {
      const XtfPing& p = rec.ping;
      if (pings == 0) first_ns = p.stamp_ns;
      last_ns = p.stamp_ns;
      ++pings;
      with_nav += p.nav_valid ? 1 : 0;
      samples = p.samples_per_side;
      range_m = p.slant_range_m;
      if (p.altitude_m > 0.0f) {
        alt_min = p.altitude_m < alt_min ? p.altitude_m : alt_min;
        alt_max = p.altitude_m > alt_max ? p.altitude_m : alt_max;
      }
    } else if (rec.kind == XtfRecordKind::kAttitude) {
      ++attitude;
    } else if (rec.kind == XtfRecordKind::kNavigation) {
      ++navigation;
    }
  }
  std::printf("packets       %" PRIu64 " (%" PRIu64 " bytes)\n", reader.packets_read(), reader.bytes_read());
  std::printf("pings         %" PRIu64 " side-scan, %u samples/side, slant range %.2f m\n", pings, samples,
              static_cast<double>(range_m));
  if (pings > 0) {
    const std::uint64_t s = first_ns / 1000000000ull;
    std::printf("time span     %.2f s from %02u:%02u:%05.2f UTC (day %" PRIu64 " since 1970)\n",
                static_cast<double>(last_ns - first_ns) * 1e-9, static_cast<unsigned>(s / 3600 % 24),
                static_cast<unsigned>(s / 60 % 60), static_cast<double>(first_ns % 60000000000ull) * 1e-9, s / 86400);
    std::printf("navigation    %" PRIu64 " of %" PRIu64 " pings with a position fix; altitude %.2f..%.2f m\n", with_nav, pings,
                static_cast<double>(alt_min), static_cast<double>(alt_max));
  }
  std::printf("other records %" PRIu64 " attitude, %" PRIu64 " navigation\n", attitude, navigation);
  std::printf("counters     ");
  for (std::size_t i = 0; i < reader.counters().size(); ++i)
    std::printf(" %s=%u", reader.counters().name_at(i), reader.counters().count_at(i));
  std::printf("\n");
  if (rc == 0 && reader.packets_read() == 0) {
    std::fprintf(stderr, "qnav xtf info: %s: a file header but no packet: nothing to read\n", path);
    return 1;
  }
  return rc;
}

std::string g_path;

void setup_xtf(CLI::App& cmd, qnav::cli::Runner& run) {
  cmd.require_subcommand(1);
  CLI::App* i = cmd.add_subcommand("info", "what an XTF file holds: header, channels, pings, time span, navigation, packet types\n"
                                           "skipped, reader counters; exit 1 on a read error or when the file holds no packet");
  qnav::cli::add_positional(*i, "FILE", g_path, "the XTF file");
  run.on(i, [] { return xtf_info(g_path.c_str()); });
}

}  // namespace

QNAV_CLI_COMMAND("xtf", "xtf info FILE: channels, pings, time span, navigation of an XTF file", setup_xtf);
