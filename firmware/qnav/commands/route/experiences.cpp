// qnav route: experiences (issue 29): `route repeat --learn` / `--no-experiences`, the experience
// listing of `route info`, and `route eval --multi-pass` (learn reverse passes at 30 % and 40 % of the
// swath, then repeat in reverse at 55-65 %: node +/-1 with and without learning; poisoning passes).
#include "firmware/qnav/commands/route/route_cmd.hpp"

#include <unistd.h>

namespace route_cmd {

// The learner's settings (--learn-min-inliers).
route::ExperienceLearnConfig learn_config() {
  route::ExperienceLearnConfig c;
  c.min_inliers = static_cast<std::uint32_t>(g_opt.learn_min_inliers);
  return c;
}

void configure_experiences(route::LocaliserConfig& lc) {
  if (!g_opt.no_experiences) pipeline::enable_experiences(lc, static_cast<std::size_t>(g_opt.max_experiences));
}

pipeline::RepeatSessionConfig repeat_session_config(route::LocaliserConfig lc, std::size_t nodes) {
  configure_experiences(lc);
  pipeline::RepeatSessionConfig c;
  c.localiser = lc;
  c.max_nodes = nodes;
  c.experiences_per_node = g_opt.no_experiences ? 0 : static_cast<std::uint16_t>(g_opt.max_experiences);
  c.learn = learn_config();
  c.backfill = g_opt.backfill;
  return c;
}

bool open_repeat_experiences(const char* route_path, pipeline::RouteRepeatSession& session) {
  if (g_opt.no_experiences) return true;
  const pipeline::ExperiencesOpened o = session.open_experiences(route_path, g_opt.learn);
  const pipeline::RouteExperiences& exps = session.experiences();
  if (!o.ok() && o.at_attach) {
    std::fprintf(stderr, "qnav route repeat: experiences: %s\n", o.status.message());
    return false;
  }
  if (!o.ok()) {
    std::fprintf(stderr, "qnav route repeat: %s%s: %s\n", route_path, ".exp", o.status.message());
    if (g_opt.learn) return false;
    std::fprintf(stderr, "qnav route repeat: WARNING: repeating without experiences\n");
    return true;
  }
  if (!session.with_experiences()) return true;
  const drivers::route_store::ExperienceOpenReport& r = o.report;
  const unsigned per_node = session.config().experiences_per_node;
  if (r.moved_stale) std::fprintf(stderr, "qnav route repeat: %s belonged to an earlier teach of this route: kept as %s.stale\n", exps.path(), exps.path());
  if (r.created) std::fprintf(stderr, "qnav route repeat: %s created (up to %u experiences per node)\n", exps.path(), per_node);
  if (r.torn_bytes > 0)
    std::fprintf(stderr, "qnav route repeat: WARNING: %s: torn tail: %llu bytes after record %u (a partial experience, %s)\n", exps.path(),
                 static_cast<unsigned long long>(r.torn_bytes), r.records, g_opt.learn ? "cut" : "ignored");
  if (r.compacted) std::fprintf(stderr, "qnav route repeat: compacted %s: %u replaced records dropped, %u kept\n", exps.path(), r.dropped, r.records);
  if (r.compact_failed)
    std::fprintf(stderr, "qnav route repeat: WARNING: %s: compaction failed (%s): learning goes on in the uncompacted file\n", exps.path(),
                 r.compact_status.message());
  if (r.damaged > 0)
    std::fprintf(stderr, "qnav route repeat: WARNING: %s: %u damaged experience records skipped (the first: record %u)\n", exps.path(), r.damaged,
                 r.first_damaged);
  std::fprintf(stderr, "qnav route repeat: %u experiences of %zu nodes from %s%s\n", r.live, session.config().max_nodes, exps.path(),
               g_opt.learn ? "; learning this pass" : "");
  return true;
}

void report_learned(FILE* f, const pipeline::RouteExperiences& exps) {
  if (!exps.learning()) return;
  const auto& c = exps.learner().counters();
  std::string why;
  for (std::size_t i = 1; i < c.size(); ++i)
    if (c.count_at(i) > 0) why += std::string(why.empty() ? "" : " ") + c.name_at(i) + "=" + std::to_string(c.count_at(i));
  std::fprintf(f, "learned %u experiences (pass %u) into %s (%u of them backfilled: tiles before a confirmed fix); tiles not learned: %s\n",
               exps.learned(), exps.pass_id() - 1, exps.path(), exps.backfilled(), why.empty() ? "none" : why.c_str());
}

bool print_route_experiences(const char* route_path, tools::RouteFileReader& reader) {
  char path[drivers::route_store::kExperiencePathBytes];
  if (!drivers::route_store::experience_path(route_path, path) || access(path, F_OK) != 0) {
    std::printf("experiences: none (no %s.exp)\n", route_path);
    return true;
  }
  pipeline::RouteExperiences exps(hal::host_file_store());
  drivers::route_store::ExperienceOpenReport r;
  Status s = exps.init(reader.node_count(), route::kMaxExperiencesPerNode, route::ExperienceLearnConfig{});
  if (s) s = exps.open(route_path, reader.params(), reader, false, &r);
  if (!s) {
    std::printf("experiences: %s: %s\n", path, s.message());
    return false;
  }
  const auto& f = exps.file();
  std::printf("experiences: %s: format %u, <= %u per node, %u records, %u live", path, f.header().version, f.header().max_per_node, r.records,
              r.live);
  if (r.torn_bytes > 0) std::printf(", torn tail %llu bytes after record %u (ignored)", static_cast<unsigned long long>(r.torn_bytes), r.records);
  if (r.damaged > 0) std::printf(", %u DAMAGED records skipped (the first: record %u)", r.damaged, r.first_damaged);
  std::printf("\n");
  const route::ExperienceIndex& ix = *exps.index();
  for (std::uint32_t n = 0; n < ix.node_count(); ++n) {
    std::string line;
    int count = 0;
    for (const route::ExperienceSlot& e : ix.slots(n)) {
      if (e.record == route::kNoExperience) continue;
      route::ExperienceMeta m;
      if (!exps.source()) continue;
      char buf[160];
      if (const_cast<drivers::route_store::ExperienceFile&>(f).load_meta(e.record, m))
        std::snprintf(buf, sizeof buf, " [pass %u %s offset %+.1f m, %u inliers, %u keypoints, record %u]", m.pass_id, m.reverse ? "reverse" : "forward",
                      static_cast<double>(m.offset_m), m.inliers, m.keypoint_count, m.record);
      else
        std::snprintf(buf, sizeof buf, " [record %u unreadable]", e.record);
      line += buf;
      ++count;
    }
    if (count > 0) std::printf("  node %u: %d%s\n", n, count, line.c_str());
  }
  return r.damaged == 0;
}

// ---------------------------------------------------------------------------------------------------
// route eval --multi-pass
namespace {

struct MpPass {
  int scored = 0, within1 = 0, learned = 0, registered = 0;
  int learned_wrong = 0;  // experiences appended to a node more than 1 from the learnt tile's true node
};

// Every tile of every pass of eval --multi-pass, one CSV row (OUT/route_multipass_tiles.csv): where
// the misses are (seabed, pass, tile position, confidence, what it registered against).
struct MpTrace {
  FILE* f = nullptr;
  long seabed = 0;
  const char* pass = "";
  int pct = 0;
};
MpTrace g_trace;

void write_trace_header() {
  std::fprintf(g_trace.f, "seabed,pass,pct,tile,tiles,true_node,estimate,confident,probability,mass_pm1,inliers,via_experience,experiences_at_true_node,"
                            "learned,registrations,experience_registrations,truth_along_m,best_node,best_inliers,true_node_inliers,learned_node,"
                            "learned_tile_true_node,via_neighbour,reg_x_m,estimate_truth_along_m\n");
}

// One pass through the repeat component (experiences optional, learning optional), as `route repeat`
// and qnavd run it, scored from kWarmupTiles on.
Status run_pass(const route::RouteParams& params, const std::vector<route::NodeMeta>& meta, route::NodeSource& nodes, const char* route_path,
                const std::vector<pipeline::RouteTile>& tiles, const std::vector<double>& node_along, bool use_exp, bool learn, MpPass& out,
                route::RouteDirection told) {
  out = MpPass{};
  pipeline::RepeatSessionConfig sc;
  sc.localiser = pipeline::default_localiser_config(told, meta.size() + 8);
  if (use_exp) pipeline::enable_experiences(sc.localiser, static_cast<std::size_t>(g_opt.max_experiences));
  sc.max_nodes = meta.size();
  sc.experiences_per_node = use_exp ? static_cast<std::uint16_t>(g_opt.max_experiences) : 0;
  sc.learn = learn_config();
  sc.backfill = g_opt.backfill;
  pipeline::RouteRepeatSession session(hal::host_file_store());
  QNAV_RETURN_IF_ERROR(session.init(sc));
  QNAV_RETURN_IF_ERROR(session.start(params, Span<const route::NodeMeta>(meta.data(), meta.size()), nodes, told == route::RouteDirection::kReverse));
  const pipeline::ExperiencesOpened opened = session.open_experiences(route_path, learn);
  QNAV_RETURN_IF_ERROR(opened.status);
  const pipeline::RouteExperiences& exps = session.experiences();
  for (std::size_t k = 0; k < tiles.size(); ++k) {
    route::LocaliserStep st;
    const pipeline::RepeatTileResult r = session.step(tiles[k], false, st);
    QNAV_RETURN_IF_ERROR(r.step);
    QNAV_RETURN_IF_ERROR(r.learn);
    if (r.learned && k > 0)  // the experience is the previous tile's
      out.learned_wrong += std::abs(static_cast<int>(exps.last_learned_node()) - true_node(node_along, tiles[k - 1].truth_along_m)) > 1;
    for (std::size_t b = 0; k > 0 && b < exps.last_backfill_count(); ++b) {  // tiles before it, learnt from that fix
      const std::size_t tile = k - 1 - exps.last_backfill_age(b);
      if (tile < tiles.size())
        out.learned_wrong += std::abs(static_cast<int>(exps.last_backfill_node(b)) - true_node(node_along, tiles[tile].truth_along_m)) > 1;
    }
    if (g_trace.f != nullptr) {
      const int tn = true_node(node_along, tiles[k].truth_along_m);
      int exp_at_true = 0;
      if (session.with_experiences() && tn >= 0)
        for (const route::ExperienceSlot& e : exps.index()->slots(static_cast<std::uint32_t>(tn))) exp_at_true += e.record != route::kNoExperience;
      std::fprintf(g_trace.f, "%ld,%s,%d,%zu,%zu,%d,%u,%d,%.3f,%.3f,%u,%d,%d,%d,%u,%u,%.1f", g_trace.seabed, g_trace.pass, g_trace.pct, k, tiles.size(), tn,
                   st.estimate, st.confident ? 1 : 0, static_cast<double>(st.probability), st.mass_pm1, st.registration.ok ? st.registration.inliers : 0u,
                   st.experience_record != route::kNoExperience ? 1 : 0, exp_at_true, r.learned ? 1 : 0, st.registrations, st.experience_registrations,
                   tiles[k].truth_along_m);
      // Diagnostics: the node measured strongest this step, the true node's measurement (-1: not
      // registered), the node an experience was appended to at this step and the true node of its tile.
      std::uint32_t best_node = 0;
      float best_sim = -1.0f, true_sim = -1.0f;
      for (const route::NodeMeasurement& m : session.repeater().localiser().last_measurements()) {
        if (m.inliers > best_sim) {
          best_sim = m.inliers;
          best_node = m.node;
        }
        if (static_cast<int>(m.node) == tn) true_sim = m.inliers;
      }
      const int ln = r.learned && k > 0 ? static_cast<int>(exps.last_learned_node()) : -1;
      const int lt = r.learned && k > 0 ? true_node(node_along, tiles[k - 1].truth_along_m) : -1;
      const double est_along = st.estimate < node_along.size() ? node_along[st.estimate] : -1.0;
      std::fprintf(g_trace.f, ",%u,%.0f,%.0f,%d,%d,%d,%.1f,%.1f\n", best_node, static_cast<double>(best_sim), static_cast<double>(true_sim), ln, lt,
                   st.via_neighbour ? 1 : 0, st.registration.sensed_to_node.x_m, est_along);
    }
    if (static_cast<int>(k) >= kWarmupTiles) {
      ++out.scored;
      out.within1 += std::abs(static_cast<int>(st.estimate) - true_node(node_along, tiles[k].truth_along_m)) <= 1;
      out.registered += st.registration.ok && st.registration.inliers > 5;
    }
  }
  out.learned = static_cast<int>(session.end());
  return Status::ok();
}

double pct(int a, int b) { return b > 0 ? 100.0 * a / b : 0.0; }

// A 10,000-node route in memory: the taught block repeated along the track (as `route eval` times it).
class ReplicatedRoute final : public route::NodeSource {
 public:
  ReplicatedRoute(const std::vector<pipeline::RouteTile>* t, std::uint32_t n, double block_m) : t_(t), n_(n), block_m_(block_m) {}
  std::uint32_t node_count() const noexcept override { return n_; }
  Status load(std::uint32_t i, route::RouteNode& out) noexcept override {
    if (i >= n_) return Status(StatusCode::kOutOfRange, "no such node");
    out = (*t_)[i % t_->size()].node;
    const double shift = block_m_ * static_cast<double>(i / t_->size());
    out.meta.index = i;
    out.meta.pose.x_m += shift;
    out.meta.along_m += shift;
    return Status::ok();
  }
  route::NodeMeta meta(std::uint32_t i) {
    route::RouteNode n;
    load(i, n).ignore();
    return n.meta;
  }

 private:
  const std::vector<pipeline::RouteTile>* t_;
  std::uint32_t n_;
  double block_m_;
};

// Every slot of every node filled: record r = node * per_node + slot -> one of the learnt experiences
// (the block node's own first, then the others in turn), its node renumbered.
class FilledExperiences final : public route::NodeSource {
 public:
  std::vector<route::RouteNode> learnt;
  std::vector<std::uint32_t> block_node;  // the learnt experience's node
  std::uint32_t per_node = 4, nodes = 0, block = 1;
  std::uint32_t node_count() const noexcept override { return nodes * per_node; }
  Status load(std::uint32_t r, route::RouteNode& out) noexcept override {
    if (r >= node_count() || learnt.empty()) return Status(StatusCode::kOutOfRange, "no such record");
    out = learnt[pick(r)];
    out.meta.index = r / per_node;
    return Status::ok();
  }
  std::size_t pick(std::uint32_t r) const noexcept {
    const std::uint32_t node = r / per_node, slot = r % per_node;
    std::uint32_t seen = 0;
    for (std::size_t k = 0; k < learnt.size(); ++k)
      if (block_node[k] == node % block && seen++ == slot) return k;
    return (static_cast<std::size_t>(node) * per_node + slot) % learnt.size();
  }
};

struct UpdateCost {
  double cpu_mean = 0.0, cpu_max = 0.0;
  std::uint32_t max_registrations = 0;
};

Status time_updates(const route::RouteParams& params, ReplicatedRoute& route_nodes, const std::vector<route::NodeMeta>& meta,
                    FilledExperiences* exp, route::ExperienceIndex* index, const std::vector<pipeline::RouteTile>& tiles, UpdateCost& out) {
  route::LocaliserConfig lc = pipeline::default_localiser_config(route::RouteDirection::kReverse, meta.size());
  if (exp != nullptr) pipeline::enable_experiences(lc, exp->per_node);
  auto rep = std::make_unique<pipeline::RouteRepeater>();
  QNAV_RETURN_IF_ERROR(rep->init(lc));
  QNAV_RETURN_IF_ERROR(rep->start(params, Span<const route::NodeMeta>(meta.data(), meta.size()), route_nodes));
  if (exp != nullptr) QNAV_RETURN_IF_ERROR(rep->attach_experiences(index, exp));
  out = UpdateCost{};
  double sum = 0.0;
  for (std::size_t k = 0; k < tiles.size(); ++k) {
    route::LocaliserStep st;
    const double c0 = cpu_ms();
    QNAV_RETURN_IF_ERROR(rep->step(tiles[k].node, k == 0 ? 0.0 : tiles[k].nav_step_m, st));
    const double c = cpu_ms() - c0;
    sum += c;
    out.cpu_max = std::max(out.cpu_max, c);
    out.max_registrations = std::max(out.max_registrations, st.registrations);
  }
  out.cpu_mean = tiles.empty() ? 0.0 : sum / static_cast<double>(tiles.size());
  return Status::ok();
}

}  // namespace

// One seabed's taught route for an experiment: the teach pass flown on seabed sb, written durably
// to route_path and opened again; node_along: each node's true along-track distance. Returns the
// command's exit code when the route file could not be written (reported), else 0 with s the status
// of the rest (a route of fewer than 2 nodes leaves train short).
struct EvalRoute {
  pipeline::SimSurvey w;
  std::vector<pipeline::RouteTile> train;
  tools::RouteFileReader reader;
  std::vector<route::NodeMeta> meta;
  std::vector<double> node_along;
};
int teach_eval_route(pipeline::RouteTilePipeline& pipe, long sb, double length_m, const std::string& route_path, EvalRoute& r, Status& s) {
  s = r.w.init(length_m, static_cast<std::uint64_t>(sb));
  if (s) s = fly(pipe, r.w, r.w.pass(0.0, false, sb == 1 ? 11 : 11 + 1000 * static_cast<std::uint64_t>(sb)), r.train);
  if (!s || r.train.size() < 2) return 0;
  const double spacing = (r.train.back().node.meta.along_m - r.train.front().node.meta.along_m) / static_cast<double>(r.train.size() - 1);
  tools::RouteFileWriter writer;
  if (!begin_route(writer, "eval", route_path.c_str(), pipeline::side_scan_route_params(pipe.config(), spacing, r.w.swath_m), true)) return 1;
  for (const pipeline::RouteTile& t : r.train)
    if (s) s = writer.append(t.node);
  if (!finish_route(writer, "eval", route_path.c_str(), s)) return 1;
  std::uint32_t bad = 0;
  s = r.reader.open(route_path.c_str());
  if (s) s = r.reader.read_all_meta(r.meta, &bad);
  for (const pipeline::RouteTile& t : r.train) r.node_along.push_back(t.truth_along_m);
  return 0;
}

namespace {

// What the experiments of eval --multi-pass and --changed-seabed share: the options, the tile
// pipeline, where to report, the clock. begin(): 0, or the command's exit code.
struct Experiment {
  double length_m = g_opt.length_m;
  long seabeds = g_opt.seabeds > 0 ? g_opt.seabeds : 3;
  std::string out_dir = g_opt.eval_out;
  FILE* log = g_opt.json ? stderr : stdout;
  pipeline::RouteTilePipeline pipe;
  Status s;
  Clock::time_point t_all;
  int begin() {
    if (const std::string e = qnav::cli::make_dirs(out_dir); !e.empty()) {
      std::fprintf(stderr, "qnav route eval: %s\n", e.c_str());
      return 1;
    }
    s = pipe.init(pipeline::default_route_tile_config());
    t_all = Clock::now();
    return 0;
  }
  // Seabed sb's route taught into er, its file OUT/route_NAME_sb.qroute (fresh: its experiences
  // removed first). 0: taught; -1: stop (s says why, or the route is shorter than 2 nodes); else the
  // command's exit code (the route file could not be written, reported).
  int teach(long sb, const char* name, bool fresh, EvalRoute& er, std::string& route_path) {
    route_path = out_dir + "/route_" + name + "_" + std::to_string(sb) + ".qroute";
    if (fresh) std::remove((route_path + ".exp").c_str());  // a fresh experiment
    if (const int rc = teach_eval_route(pipe, sb, length_m, route_path, er, s); rc != 0) return rc;
    return !s || er.train.size() < 2 ? -1 : 0;
  }
};

// eval --multi-pass: the sums over every seabed.
struct MpTotals {
  int scored = 0, before = 0, after = 0, learned = 0, poison_learned = 0, poison_passes = 0, learn_scored = 0, learn_within = 0;
  int reg_before = 0, reg_after = 0, learned_wrong = 0;
  double cost_with = -1.0, cost_with_max = -1.0, cost_without = -1.0;
};

// Cost: a 10,000-node route (the taught block repeated: ambiguous, so every update runs at the
// searching budget), every node holding --max-experiences experiences, against the same route
// without: thread CPU per update over the 60 % pass's tiles, both from memory.
Status mp_cost(FILE* log, EvalRoute& er, const std::string& route_path, const std::vector<std::vector<pipeline::RouteTile>>& tests, MpTotals& t) {
  const std::vector<pipeline::RouteTile>& train = er.train;
  const double spacing = (train.back().node.meta.along_m - train.front().node.meta.along_m) / static_cast<double>(train.size() - 1);
  const double block_m = er.node_along.back() + spacing;
  ReplicatedRoute big(&er.train, 10000, block_m);
  std::vector<route::NodeMeta> bmeta;
  for (std::uint32_t i = 0; i < 10000; ++i) bmeta.push_back(big.meta(i));
  auto filled = std::make_unique<FilledExperiences>();
  filled->per_node = static_cast<std::uint32_t>(g_opt.max_experiences);
  filled->nodes = 10000;
  filled->block = static_cast<std::uint32_t>(train.size());
  Status s;
  {
    pipeline::RouteExperiences e(hal::host_file_store());
    s = e.init(er.meta.size(), static_cast<std::uint16_t>(g_opt.max_experiences), learn_config());
    if (s) s = e.open(route_path.c_str(), er.reader.params(), er.reader, false);
    for (std::uint32_t r = 0; s && e.has_experiences() && r < e.file().records(); ++r) {
      route::RouteNode n;
      if (!e.source()->load(r, n)) continue;
      filled->block_node.push_back(n.meta.index);
      filled->learnt.push_back(n);
    }
  }
  ArenaStorage ia(route::ExperienceIndex::arena_bytes(10000, filled->per_node));
  route::ExperienceIndex bindex;
  if (s) s = bindex.init(10000, filled->per_node, ia);
  if (s) s = bindex.reset(10000);
  for (std::uint32_t n = 0; s && n < 10000; ++n)
    for (std::uint16_t k = 0; k < filled->per_node; ++k) {
      route::ExperienceMeta m;
      m.record = n * filled->per_node + k;
      m.node = n;
      m.slot = k;
      m.pass_id = 1 + k;
      s = bindex.set(m);
    }
  UpdateCost without, with;
  const std::vector<pipeline::RouteTile>& tt = tests[tests.size() > 1 ? 1 : 0];
  if (s && !filled->learnt.empty()) s = time_updates(er.reader.params(), big, bmeta, nullptr, nullptr, tt, without);
  if (s && !filled->learnt.empty()) s = time_updates(er.reader.params(), big, bmeta, filled.get(), &bindex, tt, with);
  std::fprintf(log, "  cost, 10,000 nodes (memory), %u experiences on every node: update thread CPU mean %.2f ms, max %.2f ms, <= %u registrations; "
                    "without experiences %.2f ms, max %.2f ms, <= %u registrations (%zu updates each)\n",
               filled->per_node, with.cpu_mean, with.cpu_max, with.max_registrations, without.cpu_mean, without.cpu_max, without.max_registrations,
               tt.size());
  t.cost_with = with.cpu_mean;
  t.cost_with_max = with.cpu_max;
  t.cost_without = without.cpu_mean;
  return s;
}

// One seabed of eval --multi-pass, its route taught: the test passes without experiences, the
// poisoning passes, the learning passes, the test passes again with what was learnt (and on seabed 1
// the cost on 10,000 nodes).
Status mp_seabed(Experiment& x, long sb, EvalRoute& er, const std::string& route_path, const std::vector<int>& learn_pcts,
                 const std::vector<int>& test_pcts, MpTotals& t) {
  Status s;
  pipeline::RouteTilePipeline& pipe = x.pipe;
  pipeline::SimSurvey& w = er.w;
  const std::vector<route::NodeMeta>& meta = er.meta;
  tools::RouteFileReader& reader = er.reader;
  const std::vector<double>& node_along = er.node_along;
  const auto rev = route::RouteDirection::kReverse;
  std::uint64_t seed = 50000 + 1000 * static_cast<std::uint64_t>(sb);
  // The test passes, flown once, localised without experiences now and with them after learning.
  std::vector<std::vector<pipeline::RouteTile>> tests(test_pcts.size());
  std::vector<MpPass> before(test_pcts.size()), after(test_pcts.size());
  for (std::size_t i = 0; s && i < test_pcts.size(); ++i) {
    s = fly(pipe, w, w.pass(test_pcts[i] / 100.0 * w.swath_m, true, ++seed), tests[i]);
    g_trace.pass = "without";
    g_trace.pct = test_pcts[i];
    if (s) s = run_pass(reader.params(), meta, reader, route_path.c_str(), tests[i], node_along, false, false, before[i], rev);
  }
  // Poisoning, before anything is learnt: a pass over another seabed (the wrong route) and a pass
  // flown forwards while the localiser is told it runs in reverse (its odometry contradicts every
  // registration), both with --learn.
  MpPass wrong, forced;
  std::vector<pipeline::RouteTile> tiles;
  g_trace.pass = "poison";
  g_trace.pct = 30;
  if (s) {
    pipeline::SimSurvey other;
    s = other.init(x.length_m, 900 + static_cast<std::uint64_t>(sb));
    if (s) s = fly(pipe, other, other.pass(0.3 * other.swath_m, true, ++seed), tiles);
    if (s) s = run_pass(reader.params(), meta, reader, route_path.c_str(), tiles, node_along, true, true, wrong, rev);
  }
  if (s) s = fly(pipe, w, w.pass(0.3 * w.swath_m, false, ++seed), tiles);
  if (s) s = run_pass(reader.params(), meta, reader, route_path.c_str(), tiles, node_along, true, true, forced, rev);
  t.poison_learned += wrong.learned + forced.learned;
  t.poison_passes += 2;
  // Learning passes.
  int learned = 0, learned_wrong = 0;
  for (int lp : learn_pcts) {
    MpPass l;
    g_trace.pass = "learn";
    g_trace.pct = lp;
    if (s) s = fly(pipe, w, w.pass(lp / 100.0 * w.swath_m, true, ++seed), tiles);
    if (s) s = run_pass(reader.params(), meta, reader, route_path.c_str(), tiles, node_along, true, true, l, rev);
    learned += l.learned;
    learned_wrong += l.learned_wrong;
    t.learn_scored += l.scored;
    t.learn_within += l.within1;
    std::fprintf(x.log, "  seabed %ld learn reverse %d%%: node +/-1 %5.1f%% (%d tiles), learned %d (%d on a node > 1 from the truth)\n", sb, lp,
                 pct(l.within1, l.scored), l.scored, l.learned, l.learned_wrong);
  }
  t.learned += learned;
  t.learned_wrong += learned_wrong;
  for (std::size_t i = 0; s && i < test_pcts.size(); ++i) {
    g_trace.pass = "with";
    g_trace.pct = test_pcts[i];
    s = run_pass(reader.params(), meta, reader, route_path.c_str(), tests[i], node_along, true, false, after[i], rev);
    t.scored += before[i].scored;
    t.before += before[i].within1;
    t.after += after[i].within1;
    t.reg_before += before[i].registered;
    t.reg_after += after[i].registered;
    std::fprintf(x.log, "  seabed %ld reverse %d%% (%5.1f m): node +/-1 without %5.1f%%, with experiences %5.1f%% (%d tiles); registered (> 5 inliers) %d -> %d\n", sb,
                 test_pcts[i], test_pcts[i] / 100.0 * w.swath_m, pct(before[i].within1, before[i].scored), pct(after[i].within1, after[i].scored),
                 before[i].scored, before[i].registered, after[i].registered);
  }
  std::fprintf(x.log, "  seabed %ld: %zu nodes, %d experiences learnt; poisoning: wrong route learned %d, forced mislocalisation learned %d\n", sb,
               er.train.size(), learned, wrong.learned, forced.learned);
  if (sb == 1 && s && !tests.empty()) s = mp_cost(x.log, er, route_path, tests, t);
  return s;
}

}  // namespace

int cmd_eval_multi_pass() {
  Experiment x;
  if (const int rc = x.begin(); rc != 0) return rc;
  const std::vector<int> learn_pcts{30, 40};
  const std::vector<int> test_pcts = g_opt.quick ? std::vector<int>{60} : std::vector<int>{55, 60, 65};
  MpTotals t;
  const std::string trace_path = x.out_dir + "/route_multipass_tiles.csv";
  g_trace.f = std::fopen(trace_path.c_str(), "w");
  if (g_trace.f != nullptr)
    write_trace_header();
  std::fprintf(x.log, "multi-pass: per seabed teach forwards at 0; repeat in reverse at %s%% of the swath without experiences; learn reverse passes at 30%% and 40%% "
                      "(--learn); repeat the same reverse passes with the experiences (<= %ld per node)\n",
               g_opt.quick ? "60" : "55, 60, 65", g_opt.max_experiences);
  for (long sb = 1; x.s && sb <= x.seabeds; ++sb) {
    EvalRoute er;
    std::string route_path;
    if (const int rc = x.teach(sb, "multipass", true, er, route_path); rc > 0) return rc;
    else if (rc < 0) break;
    g_trace.seabed = sb;
    x.s = mp_seabed(x, sb, er, route_path, learn_pcts, test_pcts, t);
  }
  if (g_trace.f != nullptr) std::fclose(g_trace.f);
  g_trace.f = nullptr;
  if (!x.s) {
    std::fprintf(stderr, "qnav route eval --multi-pass: %s\n", x.s.message());
    return 1;
  }
  std::fprintf(x.log, "multi-pass, %ld seabeds: reverse at %s%%: node +/-1 without experiences %.2f%%, after learning 30%% + 40%% %.2f%% (%d tiles); "
                      "registered %d -> %d; learnt %d experiences (%d on a node > 1 from the truth); poisoning passes learned %d (of %d passes); %.1f s\n",
               x.seabeds, g_opt.quick ? "60" : "55-65", pct(t.before, t.scored), pct(t.after, t.scored), t.scored, t.reg_before, t.reg_after, t.learned,
               t.learned_wrong, t.poison_learned, t.poison_passes, ms_since(x.t_all) / 1000.0);
  if (g_opt.json)
    std::printf("{\"seabeds\": %ld, \"tiles\": %d, \"node_within_1_pct_without\": %.2f, \"node_within_1_pct_with\": %.2f, \"registered_without\": %d, "
                "\"registered_with\": %d, \"learned\": %d, \"learned_wrong_node\": %d, \"learn_pass_node_within_1_pct\": %.2f, \"poisoning_learned\": %d, \"max_experiences\": %ld, "
                "\"update_cpu_ms_10000_nodes_with\": %.2f, \"update_cpu_ms_10000_nodes_with_max\": %.2f, \"update_cpu_ms_10000_nodes_without\": %.2f}\n",
                x.seabeds, t.scored, pct(t.before, t.scored), pct(t.after, t.scored), t.reg_before, t.reg_after, t.learned, t.learned_wrong,
                pct(t.learn_within, t.learn_scored), t.poison_learned, g_opt.max_experiences, t.cost_with, t.cost_with_max, t.cost_without);
  return 0;
}

// ---------------------------------------------------------------------------------------------------
// route eval --changed-seabed: the seabed changed between the teach and the repeats (ripples moved,
// patches of changed reflectivity, rocks gone or new), at several degrees; repeats at 20 % forwards
// and in reverse, localised without experiences, then again after one forward repeat at 0 % over the
// changed seabed was learnt.
int cmd_eval_changed_seabed() {
  Experiment x;
  if (const int rc = x.begin(); rc != 0) return rc;
  const double length_m = x.length_m;
  const long seabeds = x.seabeds;
  FILE* log = x.log;
  const std::vector<int> degrees{20, 40, 60};
  pipeline::RouteTilePipeline& pipe = x.pipe;
  Status& s = x.s;
  const auto t_all = x.t_all;
  std::vector<int> scored(degrees.size(), 0), before(degrees.size(), 0), after(degrees.size(), 0), learnt(degrees.size(), 0);
  // Every tile of every pass, as eval --multi-pass writes them (pass: without_fwd/_rev, learn, with_fwd/_rev; pct: the change).
  g_trace.f = std::fopen((x.out_dir + "/route_changed_tiles.csv").c_str(), "w");
  if (g_trace.f != nullptr) write_trace_header();
  std::fprintf(log, "changed seabed: per seabed and degree d: ripples moved by d%% x 2 wavelengths, d%% of 12 m cells with reflectivity +/-0.3, d%% of rock cells "
                    "flipped (a rock gone or new); repeats at 20%% forwards and reverse without experiences, then after learning one forward repeat at 0%% "
                    "over the changed seabed\n");
  for (long sb = 1; s && sb <= seabeds; ++sb) {
    EvalRoute er;
    std::string route_path;
    if (const int rc = x.teach(sb, "changed", false, er, route_path); rc > 0) return rc;
    else if (rc < 0) break;
    pipeline::SimSurvey& w = er.w;
    const std::vector<route::NodeMeta>& meta = er.meta;
    tools::RouteFileReader& reader = er.reader;
    const std::vector<double>& node_along = er.node_along;
    std::uint64_t seed = 70000 + 1000 * static_cast<std::uint64_t>(sb);
    g_trace.seabed = sb;
    for (std::size_t di = 0; s && di < degrees.size(); ++di) {
      const float f = static_cast<float>(degrees[di]) / 100.0f;
      pipeline::SimSurvey changed;
      s = changed.init(length_m, static_cast<std::uint64_t>(sb));
      sidescan::SeabedConfig sc = w.seabed.config();
      sc.change_fraction = f;
      sc.change_ripple_shift_m = f * 2.0f * sc.ripple_wavelength_m;
      sc.change_seed = 17 + static_cast<std::uint64_t>(sb);
      sc.change_irregular = g_opt.change_irregular;
      if (s) s = changed.seabed.init(sc);
      std::remove((route_path + ".exp").c_str());
      g_trace.pct = degrees[di];
      std::vector<std::vector<pipeline::RouteTile>> tests(2);
      MpPass b[2], a[2], l;
      for (int r = 0; s && r < 2; ++r) {
        s = fly(pipe, changed, changed.pass(0.2 * changed.swath_m, r == 1, ++seed), tests[static_cast<std::size_t>(r)]);
        g_trace.pass = r == 1 ? "without_rev" : "without_fwd";
        if (s)
          s = run_pass(reader.params(), meta, reader, route_path.c_str(), tests[static_cast<std::size_t>(r)], node_along, false, false, b[r],
                       r == 1 ? route::RouteDirection::kReverse : route::RouteDirection::kForward);
      }
      std::vector<pipeline::RouteTile> tiles;
      if (s) s = fly(pipe, changed, changed.pass(0.0, false, ++seed), tiles);
      g_trace.pass = "learn";
      if (s) s = run_pass(reader.params(), meta, reader, route_path.c_str(), tiles, node_along, true, true, l, route::RouteDirection::kForward);
      for (int r = 0; s && r < 2; ++r) {
        g_trace.pass = r == 1 ? "with_rev" : "with_fwd";
        s = run_pass(reader.params(), meta, reader, route_path.c_str(), tests[static_cast<std::size_t>(r)], node_along, true, false, a[r],
                     r == 1 ? route::RouteDirection::kReverse : route::RouteDirection::kForward);
      }
      if (!s) break;
      for (int r = 0; r < 2; ++r) {
        scored[di] += b[r].scored;
        before[di] += b[r].within1;
        after[di] += a[r].within1;
      }
      learnt[di] += l.learned;
      std::fprintf(log, "  seabed %ld change %d%%: learnt %d (%d wrong node); 20%% forward node +/-1 %5.1f%% -> %5.1f%%, reverse %5.1f%% -> %5.1f%%; "
                        "registered %d -> %d, %d -> %d\n",
                   sb, degrees[di], l.learned, l.learned_wrong, pct(b[0].within1, b[0].scored), pct(a[0].within1, a[0].scored), pct(b[1].within1, b[1].scored),
                   pct(a[1].within1, a[1].scored), b[0].registered, a[0].registered, b[1].registered, a[1].registered);
    }
  }
  if (g_trace.f != nullptr) std::fclose(g_trace.f);
  g_trace.f = nullptr;
  if (!s) {
    std::fprintf(stderr, "qnav route eval --changed-seabed: %s\n", s.message());
    return 1;
  }
  std::string json = "{\"seabeds\": " + std::to_string(seabeds) + ", \"degrees\": [";
  for (std::size_t di = 0; di < degrees.size(); ++di) {
    std::fprintf(log, "changed seabed %d%%, %ld seabeds: node +/-1 without learning %.2f%%, after learning one repeat %.2f%% (%d tiles, %d experiences)\n",
                 degrees[di], seabeds, pct(before[di], scored[di]), pct(after[di], scored[di]), scored[di], learnt[di]);
    char buf[200];
    std::snprintf(buf, sizeof buf, "%s{\"change_pct\": %d, \"tiles\": %d, \"node_within_1_pct_without\": %.2f, \"node_within_1_pct_with\": %.2f, \"learned\": %d}",
                  di ? ", " : "", degrees[di], scored[di], pct(before[di], scored[di]), pct(after[di], scored[di]), learnt[di]);
    json += buf;
  }
  std::fprintf(log, "%.1f s\n", ms_since(t_all) / 1000.0);
  if (g_opt.json) std::printf("%s]}\n", json.c_str());
  return 0;
}

}  // namespace route_cmd
