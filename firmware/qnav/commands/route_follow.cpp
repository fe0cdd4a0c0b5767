// qnav route follow --sim: the closed route-following loop on the simulator (issue 27), against dead
// reckoning alone. Per seed: teach a route on the SimSurvey (seabed = seed), then fly one repeat
// steered by the RouteAutopilot on qnav's CAN guidance and one steered by the same autopilot on dead
// reckoning alone against the taught track, with the same drift, current, start and seed
// (firmware/pipeline/closed_loop.hpp). Prints per-run lines and the pooled truth cross-track figures;
// --json one object on stdout; --csv the tracks (taught, dead reckoning, qnav); --plot a PNG of them
// (scripts/route_follow_plot.py). docs/route.md ("Closed loop") has the law and the measured table.
#include "firmware/qnav/commands/route_follow.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "firmware/cli/cli_app.hpp"
#include "firmware/pipeline/closed_loop.hpp"
#include "firmware/qnav/command.hpp"

namespace {

using namespace qnav;

struct FollowOptions {
  std::string seeds = "1:2", csv, plot;
  double length_m = 2000.0, heading_bias_deg = 1.0, dvl_scale_pct = 1.0, current_mps = 0.2, start_offset_pct = 0.0;
  double dropout_every_s = 600.0, lookahead_m = 25.0;
  bool sim = false, reverse = false, json = false, hold_on_track = false;
};
FollowOptions g_f;

int usage(const char* what) {
  std::fprintf(stderr, "qnav route follow: %s (qnav help route follow)\n", what);
  return 2;
}

bool parse_seeds(const std::string& s, long& a, long& b) {
  const std::size_t c = s.find(':');
  if (c == std::string::npos) return false;
  char* e1 = nullptr;
  char* e2 = nullptr;
  const std::string sa = s.substr(0, c), sb = s.substr(c + 1);
  if (sa.empty() || sb.empty()) return false;
  a = std::strtol(sa.c_str(), &e1, 10);
  b = std::strtol(sb.c_str(), &e2, 10);
  return *e1 == '\0' && *e2 == '\0' && a >= 0 && b > a && b - a <= 100 && b <= 2147483647L;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double idx = p / 100.0 * static_cast<double>(v.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(idx)), hi = std::min(v.size() - 1, lo + 1);
  return v[lo] + (idx - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

struct GuideStats {
  std::vector<double> all;  // |cross-track| of every ping of every run
  std::vector<double> end_offset, join, run_p95, run_max;
  int reached = 0, runs = 0, joined = 0;
};

void add_run(GuideStats& g, const pipeline::ClosedLoopResult& r, double spacing_m) {
  g.all.insert(g.all.end(), r.abs_cross_track_m.begin(), r.abs_cross_track_m.end());
  g.end_offset.push_back(r.end_offset_m);
  g.run_p95.push_back(percentile(r.abs_cross_track_m, 95.0));
  g.run_max.push_back(r.max_cross_track_m);
  if (r.join_distance_m >= 0.0) {
    g.join.push_back(r.join_distance_m);
    ++g.joined;
  }
  g.reached += r.stopped && r.end_offset_m <= spacing_m;
  ++g.runs;
}

void print_json_guide(const char* name, const GuideStats& g, bool last) {
  auto mx = [](const std::vector<double>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); };
  std::printf(
      "  \"%s\": {\"cross_track_p50_m\": %.2f, \"cross_track_p95_m\": %.2f, \"cross_track_max_m\": %.2f, "
      "\"end_offset_m\": %.2f, \"end_offset_p50_m\": %.2f, \"end_offset_min_m\": %.2f, \"reached_end_pct\": %.1f, "
      "\"worst_run_cross_track_p95_m\": %.2f, "
      "\"join_distance_p50_m\": %.1f, \"join_distance_max_m\": %.1f, \"joined_pct\": %.1f}%s\n",
      name, percentile(g.all, 50.0), percentile(g.all, 95.0), mx(g.run_max), mx(g.end_offset),
      percentile(g.end_offset, 50.0),
      g.end_offset.empty() ? 0.0 : *std::min_element(g.end_offset.begin(), g.end_offset.end()),
      g.runs ? 100.0 * g.reached / g.runs : 0.0, mx(g.run_p95), g.join.empty() ? -1.0 : percentile(g.join, 50.0),
      g.join.empty() ? -1.0 : mx(g.join), g.runs ? 100.0 * g.joined / g.runs : 0.0, last ? "" : ",");
}

int cmd_follow() {
  if (!g_f.sim) return usage("give --sim (the closed loop runs on the side-scan simulator)");
  long a = 0, b = 0;
  if (!parse_seeds(g_f.seeds, a, b))
    return usage(
        ("--seeds: '" + g_f.seeds + "' is not A:B with 0 <= A < B and at most 100 seeds (seeds A to B-1)").c_str());
  if (!g_f.plot.empty() && g_f.csv.empty()) return usage("--plot needs --csv (the plot is drawn from it)");
  const auto t_start = std::chrono::steady_clock::now();
  FILE* csv = nullptr;
  if (!g_f.csv.empty()) {
    csv = std::fopen(g_f.csv.c_str(), "w");
    if (csv == nullptr) {
      std::fprintf(stderr, "qnav route follow: cannot write --csv %s\n", g_f.csv.c_str());
      return 1;
    }
    std::fprintf(csv, "seed,track,t_s,north_m,east_m,cross_track_m,along_m,travelled_m,mode,dvl_lost\n");
  }
  FILE* log = g_f.json ? stderr : stdout;
  GuideStats qs, ds;
  double swath = 0.0, spacing = 0.0;
  int runs = 0;
  for (long seed = a; seed < b; ++seed) {
    pipeline::TaughtSimRoute route;
    const auto t0 = std::chrono::steady_clock::now();
    Status s = pipeline::teach_closed_loop_route(g_f.length_m, static_cast<std::uint64_t>(seed), route);
    if (!s) {
      std::fprintf(stderr, "qnav route follow: seed %ld: teach: %s\n", seed, s.message());
      if (csv) std::fclose(csv);
      return 1;
    }
    swath = route.survey.swath_m;
    spacing = route.spacing_m;
    const double teach_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (csv) {
      for (const Vec2d& p : route.survey.route.waypoints_ne)
        std::fprintf(csv, "%ld,taught,0,%.2f,%.2f,0,0,0,,0\n", seed, p.x(), p.y());
    }
    // The drift of this seed: the signs alternate with the seed, the current's direction is seeded.
    pipeline::FollowDrift drift;
    drift.heading_bias_deg = g_f.heading_bias_deg;
    drift.dvl_scale_pct = g_f.dvl_scale_pct;
    drift.current_mps = g_f.current_mps;
    drift.dropout_every_s = g_f.dropout_every_s;
    pipeline::ClosedLoopScenario sc =
        pipeline::follow_scenario(static_cast<std::uint64_t>(seed), g_f.reverse, g_f.start_offset_pct / 100.0 * swath, drift);
    sc.autopilot.lookahead_m = g_f.lookahead_m;
    sc.autopilot.follow_track_on_hold = g_f.hold_on_track;
    for (const pipeline::Guide guide : {pipeline::Guide::kQnav, pipeline::Guide::kDeadReckoning}) {
      pipeline::ClosedLoopResult r;
      const auto t1 = std::chrono::steady_clock::now();
      long n = 0;
      const char* track = pipeline::to_string(guide);
      s = pipeline::run_closed_loop(route, sc, guide, 0.1 * swath, r, [&](const pipeline::TrackSample& smp) {
        if (csv && (n++ % 25) == 0)  // every 5 s
          std::fprintf(csv, "%ld,%s,%.1f,%.2f,%.2f,%.2f,%.1f,%.1f,%s,%d\n", seed, track, smp.t_s, smp.truth.x_m,
                       smp.truth.y_m, smp.cross_track_m, smp.along_m, smp.travelled_m, pipeline::to_string(smp.mode),
                       smp.dvl_lost ? 1 : 0);
      });
      if (!s) {
        std::fprintf(stderr, "qnav route follow: seed %ld %s: %s\n", seed, track, s.message());
        if (csv) std::fclose(csv);
        return 1;
      }
      add_run(guide == pipeline::Guide::kQnav ? qs : ds, r, spacing);
      ++runs;
      std::fprintf(log,
                   "seed %ld %-14s %s: cross-track p50 %.1f p95 %.1f max %.1f m; end %s, %.1f m off (along %+.1f m); "
                   "travelled %.0f m; "
                   "join %.0f m; fixes %u steered / %u tiles; dvl dropouts %.0f s; %.1f s (teach %.1f s)\n",
                   seed, track, g_f.reverse ? "reverse" : "forward", percentile(r.abs_cross_track_m, 50.0),
                   percentile(r.abs_cross_track_m, 95.0), r.max_cross_track_m,
                   r.stopped ? "reached" : "NOT reached (travel limit)", r.end_offset_m, r.end_along_m, r.travelled_m,
                   r.join_distance_m, r.steer_fixes, r.tiles, r.dropout_s,
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count(), teach_s);
    }
  }
  if (csv && std::fclose(csv) != 0) {
    std::fprintf(stderr, "qnav route follow: writing --csv %s failed\n", g_f.csv.c_str());
    return 1;
  }
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  auto summary = [&](const char* name, const GuideStats& g) {
    std::fprintf(log,
                 "%-14s cross-track p50 %.1f m, p95 %.1f m (%.1f %% of swath), max %.1f m (%.1f %%); end offset max "
                 "%.1f m; reached end %d/%d\n",
                 name, percentile(g.all, 50.0), percentile(g.all, 95.0), 100.0 * percentile(g.all, 95.0) / swath,
                 g.run_max.empty() ? 0.0 : *std::max_element(g.run_max.begin(), g.run_max.end()),
                 g.run_max.empty() ? 0.0 : 100.0 * *std::max_element(g.run_max.begin(), g.run_max.end()) / swath,
                 g.end_offset.empty() ? 0.0 : *std::max_element(g.end_offset.begin(), g.end_offset.end()), g.reached,
                 g.runs);
  };
  std::fprintf(log,
               "route follow: %d runs, %.0f m route, swath %.1f m, node spacing %.1f m, %s, heading bias %.2f deg, DVL "
               "scale %.2f %%, current %.2f m/s, "
               "start offset %.0f %% of swath%s; %.0f s\n",
               runs, g_f.length_m, swath, spacing, g_f.reverse ? "reverse" : "forward", g_f.heading_bias_deg,
               g_f.dvl_scale_pct, g_f.current_mps, g_f.start_offset_pct,
               g_f.hold_on_track ? ", on HoldCourse the taught track on dead reckoning" : "", wall_s);
  summary("qnav", qs);
  summary("dead_reckoning", ds);
  if (g_f.json) {
    std::printf(
        "{\n  \"swath_m\": %.2f, \"runs\": %d, \"seeds\": \"%s\", \"length_m\": %.0f, \"reverse\": %s, "
        "\"node_spacing_m\": %.2f,\n",
        swath, runs, g_f.seeds.c_str(), g_f.length_m, g_f.reverse ? "true" : "false", spacing);
    std::printf(
        "  \"heading_bias_deg\": %.3f, \"dvl_scale_pct\": %.3f, \"current_mps\": %.3f, \"start_offset_pct\": %.1f, "
        "\"hold_on_track\": %s, \"wall_s\": %.1f,\n",
        g_f.heading_bias_deg, g_f.dvl_scale_pct, g_f.current_mps, g_f.start_offset_pct,
        g_f.hold_on_track ? "true" : "false", wall_s);
    print_json_guide("qnav", qs, false);
    print_json_guide("dead_reckoning", ds, true);
    std::printf("}\n");
  }
  if (!g_f.plot.empty()) {
    // The script beside this source tree (as `qnav map`'s plot), or under $QNAV_SCRIPTS.
    std::string root = __FILE__;  // .../firmware/qnav/commands/route_follow.cpp
    for (int i = 0; i < 4 && root.find('/') != std::string::npos; ++i) root = root.substr(0, root.find_last_of('/'));
    const char* dir = std::getenv("QNAV_SCRIPTS");
    const std::string script = (dir ? std::string(dir) : root + "/scripts") + "/route_follow_plot.py";
    const std::string cmd = "/usr/bin/python3 '" + script + "' '" + g_f.csv + "' '" + g_f.plot + "'";
    if (std::system(cmd.c_str()) != 0) {
      std::fprintf(stderr, "qnav route follow: the plot failed (%s)\n", cmd.c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace

void setup_route_follow(CLI::App& route_cmd, qnav::cli::Runner& run) {
  using qnav::cli::add_flag;
  using qnav::cli::add_number;
  using qnav::cli::add_text;
  CLI::App* f = route_cmd.add_subcommand(
      "follow",
      "closed loop on the simulator: an autopilot steering on qnav's CAN guidance against the same\n"
      "autopilot on dead reckoning alone (truth cross-track from the taught track)");
  add_flag(*f, "--sim", g_f.sim, "fly the loop on the side-scan simulator (the only source so far)");
  add_text(*f, "--seeds", g_f.seeds,
           "seeds A to B-1 (each: its own seabed, speckle, drift signs and current direction)")
      ->type_name("A:B");
  add_number(*f, "--length-m", g_f.length_m, "length of the simulated route", "m", 400, 50000);
  add_number(*f, "--heading-bias-deg", g_f.heading_bias_deg, "compass bias (sign alternates with the seed)", "deg", 0,
             10);
  add_number(*f, "--dvl-scale-pct", g_f.dvl_scale_pct, "DVL scale error (sign alternates every 2 seeds)", "%", 0, 10);
  add_number(*f, "--current-mps", g_f.current_mps, "water current, direction seeded", "m/s", 0, 1);
  add_number(*f, "--start-offset-pct", g_f.start_offset_pct, "start this far right of the route (direction of travel)",
             "% of the swath", -100, 100);
  add_number(*f, "--dvl-dropout-every-s", g_f.dropout_every_s, "mean time between DVL dropouts of 10-40 s (0 = none)",
             "s", 0, 1e6);
  add_number(*f, "--lookahead-m", g_f.lookahead_m, "the autopilot's line-of-sight look-ahead", "m", 10, 1000);
  add_flag(
      *f, "--hold-on-track", g_f.hold_on_track,
      "on HoldCourse (and from the start) keep following the taught track on dead reckoning instead of holding course");
  add_flag(*f, "--reverse", g_f.reverse, "follow the route backwards (from its end to its start)");
  add_flag(*f, "--json", g_f.json, "one JSON object on stdout (the per-run lines on stderr)");
  add_text(*f, "--csv", g_f.csv, "write the tracks (taught, qnav, dead_reckoning; a row every 5 s) here")
      ->type_name("FILE");
  add_text(*f, "--plot", g_f.plot, "draw the CSV's tracks into this PNG (needs --csv; scripts/route_follow_plot.py)")
      ->type_name("PNG");
  run.on(f, cmd_follow);
}
