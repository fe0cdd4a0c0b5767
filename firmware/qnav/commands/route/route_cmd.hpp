// qnav route: what the subcommands' files share (firmware/qnav/commands/route.cpp: train, info,
// repeat and the command's options; route/eval.cpp: eval; route/recorded.cpp: xtf and the recorded
// passes of train / repeat; route/camera.cpp: camera; route_follow.cpp: follow). Tool side only.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <sys/stat.h>
#include <time.h>
#include <vector>
#include "firmware/cli/cli_app.hpp"
#include "firmware/qnav/command.hpp"
#include "firmware/qnav/commands/route_follow.hpp"
#include "firmware/tools/png_writer.hpp"
#include "drivers/route_store/route_open.hpp"
#include "firmware/tools/route_file.hpp"
#include "firmware/pipeline/route_defaults.hpp"
#include "firmware/pipeline/route_experiences.hpp"
#include "firmware/pipeline/route_repeater.hpp"
#include "firmware/pipeline/route_repeat_session.hpp"
#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "firmware/pipeline/sim_survey.hpp"
#include "firmware/pipeline/vector_node_source.hpp"
#include "firmware/tools/sonar_file.hpp"
#include "drivers/sidescan/byte_source.hpp"
#include "drivers/sidescan/xtf_reader.hpp"
#include "drivers/stereo_sim/mars_yard.hpp"
#include "nav/route/camera_tile.hpp"
#include "nav/route/route_localiser.hpp"

namespace route_cmd {

using namespace qnav;
using Clock = std::chrono::steady_clock;

// The options of every route subcommand (one invocation per process), filled by the strict parser
// (setup_route at the end of this file declares them with their units, defaults and ranges).
struct RouteOptions {
  std::string out, route, sonar, csv, xtf, pings, train, repeat, nav = "fix", info_file;
  std::string eval_out = "route_eval";
  double length_m = 2000.0, offset_pct = 0.0, heading_offset_deg = 0.0;
  double camera_length_m = 12.0;
  double framing_length_m = 1000.0;
  double framing_entry_prior = pipeline::kDefaultEntryPrior;  // route framing: the repeat's start belief, as qnavd's route.entry_prior
  long framing_seabed = 1;        // route framing: the simulated seabed (and the survey's seed)
  std::string framing_only;       // route framing: "RATE:SPEED" runs that configuration alone (and the reference)
  bool trace_sides = false;       // route framing: a log line per tile whose side was decided wrong
  long seed = 1, camera_seed = 7, dump_tile = -1, seabeds = 0, lines = 0, stride = 0;
  double tile_length_m = 0.0, tile_stride_m = 0.0;  // recorded passes: 0 = from the swath (route_defaults)
  bool sim = false, force = false, reverse = false, json = false, quick = false, no_align = false;
  bool no_speckle = false, no_ripples = false;  // route framing: the simulator without speckle / sand ripples (diagnosis)
  // Experiences (issue 29, route/experiences.cpp).
  bool learn = false, no_experiences = false, multi_pass = false, changed_seabed = false, backfill = false, change_irregular = false;
  long max_experiences = 4, learn_min_inliers = 8;
};
extern RouteOptions g_opt;
constexpr int kWarmupTiles = 2;  // tiles before scoring (uniform start; the paper's first tile copies eq. 9)

const char* opt_or_null(const std::string& s);
double ms_since(Clock::time_point t0);
// CPU time of this thread (the machine is shared: wall time includes other people's work).
double cpu_ms();
// Collects the tiles of one simulated pass.
Status fly(pipeline::RouteTilePipeline& pipe, const pipeline::SimSurvey& w, const sidescan::TrajectoryConfig& t, std::vector<pipeline::RouteTile>& out);
using pipeline::VectorNodeSource;
using TileSource = VectorNodeSource<pipeline::RouteTile>;
// A usage error the parser cannot see (a combination of options): named, exit 2.
int usage(const char* cmd, const char* what);
// Route files: teaching never destroys a route before its replacement is complete (route.cpp).
bool begin_route(tools::RouteFileWriter& w, const char* cmd, const char* out, const route::RouteParams& p, bool force,
                 tools::RouteWriterOptions o = tools::RouteWriterOptions{});
bool finish_route(tools::RouteFileWriter& w, const char* cmd, const char* out, Status taught);
bool open_route_for_repeat(const char* path, tools::RouteFileReader& reader, std::vector<route::NodeMeta>& meta);
// The repeat CSV (--csv): header, one row per tile, close with a check.
FILE* open_repeat_csv();
void write_repeat_row(FILE* f, long tile, int true_node, const route::LocaliserStep& st, const char* true_side, long ping_first, long ping_last);
bool close_csv(FILE* f);
int true_node(const std::vector<double>& node_truth_along, double along);
route::RouteSide expected_side(double lateral_m, bool reverse, double deadband);

int cmd_eval();                       // route/eval.cpp
int cmd_framing();                    // route/eval.cpp: tiles in metres at several ping rates and speeds
int cmd_xtf();                        // route/recorded.cpp
int cmd_train_file(const char* path);
int cmd_repeat_file(const char* path);
int cmd_camera();                     // route/camera.cpp
// route/experiences.cpp: the route's experiences for a repeat (ROUTE.exp; --learn appends to it,
// --no-experiences ignores it).
// The repeat component's settings for a pass of the tool (--no-experiences, --max-experiences,
// --learn-min-inliers, --backfill) on a route of `nodes` nodes.
pipeline::RepeatSessionConfig repeat_session_config(route::LocaliserConfig lc, std::size_t nodes);
// Opens the route's experiences for the session (--learn: for appending) and reports what was read;
// false (reported) when the pass cannot go on: learning without a usable companion, or a companion
// the localiser refuses.
bool open_repeat_experiences(const char* route_path, pipeline::RouteRepeatSession& session);
// The localiser configuration with experiences enabled when the repeat may use them.
void configure_experiences(route::LocaliserConfig& lc);
void report_learned(FILE* f, const pipeline::RouteExperiences& exps);
// route info: the experiences of every node (ROUTE.exp), if any; false when the companion is damaged.
bool print_route_experiences(const char* route_path, tools::RouteFileReader& reader);
int cmd_eval_multi_pass();            // route/experiences.cpp: eval --multi-pass
int cmd_eval_changed_seabed();        // route/experiences.cpp: eval --changed-seabed

}  // namespace route_cmd
