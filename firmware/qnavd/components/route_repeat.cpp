#include "firmware/qnavd/components/route_repeat.hpp"

#include "drivers/route_store/route_open.hpp"
#include "firmware/pipeline/route_can.hpp"
#include "firmware/qnavd/deployment.hpp"

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

Status RouteRepeat::init(StaticMemory* mem, qc::QnavCanPublisher& publisher) {
  publisher_ = &publisher;
  pipeline::RepeatSessionConfig sc;
  sc.localiser = repeat_localiser_config(*ctx_.cfg);
  sc.max_nodes = ctx_.cfg->max_nodes;
  sc.experiences_per_node = ctx_.cfg->max_experiences;
  sc.entry_prior = ctx_.cfg->route_entry_prior;
  Result<Arena*> a = arena_.take(mem, "localiser", route::RouteLocaliser::arena_bytes(sc.localiser));
  if (!a) return a.status();
  QNAV_RETURN_IF_ERROR(session_.init(sc, a.value()));
  meta_.reserve(ctx_.cfg->max_nodes);
  reader_.reserve(route::record_bytes(route::kMaxKeypointsPerNode));
  return Status::ok();
}

ModeReject RouteRepeat::probe(std::uint16_t route_id) noexcept {
  char path[1024];
  route_file_path(*ctx_.cfg, route_id, "", path, sizeof path);
  Result<int> probe = store_.open(path, hal::FileMode::kRead);
  if (probe) {
    store_.close(*probe);
    return ModeReject::kNone;
  }
  if (ctx_.log) std::fprintf(ctx_.log, "{\"event\":\"route_refused\",\"file\":\"%s\",\"why\":\"%s\"}\n", path, probe.status().message());
  return probe.status().code() == StatusCode::kNotFound ? ModeReject::kRouteMissing : ModeReject::kStorage;
}

ModeReject RouteRepeat::enter(std::uint16_t route_id, bool reverse) noexcept {
  char path[1024];
  route_file_path(*ctx_.cfg, route_id, "", path, sizeof path);
  FILE* log = ctx_.log;
  using drivers::route_store::RepeatOpen;
  const drivers::route_store::RepeatOpenReport r = drivers::route_store::open_route_for_repeat(reader_, path, meta_, ctx_.cfg->max_nodes);
  if (!drivers::route_store::usable(r.outcome)) {
    if (log && r.outcome == RepeatOpen::kDamaged)
      std::fprintf(log, "{\"event\":\"route_damaged\",\"file\":\"%s\",\"first_bad_node\":%u,\"why\":\"%s\"}\n", path, r.first_bad_node, r.why.message());
    else if (log)
      std::fprintf(log, "{\"event\":\"route_refused\",\"file\":\"%s\",\"why\":\"%s\"}\n", path, r.why.message());
    switch (r.outcome) {
      case RepeatOpen::kMissing: return ModeReject::kRouteMissing;
      case RepeatOpen::kStorage: return ModeReject::kStorage;
      case RepeatOpen::kTooLong: return ModeReject::kRouteTooLong;
      case RepeatOpen::kTooShort: return ModeReject::kRouteTooShort;
      default: route_damaged_ = true; return ModeReject::kRouteDamaged;  // unreadable or damaged: the file needs attention
    }
  }
  if ((r.cut_off || r.torn_bytes > 0) && log) {
    // Still usable (every complete node was checked), but the autopilot's operator should know.
    std::fprintf(log, "{\"event\":\"route_cut_off\",\"file\":\"%s\",\"nodes\":%u,\"torn_bytes\":%llu,\"partial_node_dropped\":%s,\"end\":\"%s\"}\n", path,
                 r.file_nodes, static_cast<unsigned long long>(r.torn_bytes), r.torn_bytes > 0 ? "true" : "false",
                 drivers::route_store::to_string(reader_.end()));
  }
  // A damaged node with a good prefix before it: the repeat runs on the prefix, and the fault stays
  // raised while it does (the route file needs attention).
  const bool prefix_only = r.outcome == RepeatOpen::kGoodPrefix;
  if (prefix_only && log)
    std::fprintf(log, "{\"event\":\"route_damaged\",\"file\":\"%s\",\"first_bad_node\":%u,\"why\":\"%s\",\"repeating_nodes\":%u,\"nodes_unused\":%u}\n",
                 path, r.first_bad_node, r.why.message(), r.nodes_used, r.file_nodes - r.nodes_used);
  const Status s = session_.start(reader_.params(), Span<const route::NodeMeta>(meta_.data(), meta_.size()), reader_, reverse);
  if (!s) {
    // e.g. a route taught with another sensor or tile geometry than this configuration's
    if (log) std::fprintf(log, "{\"event\":\"route_refused\",\"file\":\"%s\",\"why\":\"%s\"}\n", path, s.message());
    reader_.close();
    return ModeReject::kRouteMismatch;
  }
  open_experiences(path);
  route_damaged_ = prefix_only;  // a good route clears the fault
  return ModeReject::kNone;
}

// The route's experiences for this repeat (read, or with route.learn opened for appending).
void RouteRepeat::open_experiences(const char* path) noexcept {
  const pipeline::ExperiencesOpened o = session_.open_experiences(path, ctx_.cfg->route_learn);
  const pipeline::RouteExperiences& e = session_.experiences();
  if (!o.ok()) {
    ++experience_errors_;
    if (ctx_.log) std::fprintf(ctx_.log, "{\"event\":\"route_experiences_refused\",\"file\":\"%s\",\"why\":\"%s\"}\n", e.path(), o.status.message());
    return;
  }
  if (!session_.with_experiences()) return;  // no companion, not learning
  const drivers::route_store::ExperienceOpenReport& rep = o.report;
  if (ctx_.log)
    std::fprintf(ctx_.log,
                 "{\"event\":\"route_experiences\",\"file\":\"%s\",\"learn\":%s,\"live\":%u,\"records\":%u,\"damaged\":%u,"
                 "\"torn_bytes\":%llu,\"created\":%s,\"moved_stale\":%s,\"compacted\":%s,\"dropped\":%u,\"compact_failed\":%s}\n",
                 e.path(), e.learning() ? "true" : "false", rep.live, rep.records, rep.damaged, static_cast<unsigned long long>(rep.torn_bytes),
                 rep.created ? "true" : "false", rep.moved_stale ? "true" : "false", rep.compacted ? "true" : "false", rep.dropped,
                 rep.compact_failed ? "true" : "false");
}

void RouteRepeat::leave() noexcept {
  const bool learning = session_.with_experiences() && session_.experiences().learning();
  const std::uint32_t pass_learned = session_.end();
  if (ctx_.log && learning)
    std::fprintf(ctx_.log, "{\"event\":\"route_learned\",\"file\":\"%s\",\"experiences\":%u}\n", session_.experiences().path(), pass_learned);
  reader_.close();
}

bool RouteRepeat::step(const pipeline::RouteTile& t, std::uint32_t tile_seq, bool dvl_lost, route::LocaliserStep& out) noexcept {
  const pipeline::RepeatTileResult r = session_.step(t, dvl_lost, out);
  if (r.learned) ++learned_;
  if (!r.learn) {
    ++experience_errors_;
    if (ctx_.log)
      std::fprintf(ctx_.log, "{\"event\":\"error\",\"what\":\"route experiences: %s: %s\"}\n", session_.experiences().path(), r.learn.message());
  }
  if (!r.step) ++step_errors_;
  if (r.step && out.guidance.registration_rejected) ++registrations_rejected_;
  // The next node in the direction of travel is one spacing ahead of the node the offsets refer to
  // (the taught nodes' own spacing, as the localiser's motion model uses it); values in the DBC ranges.
  pipeline::route_can_messages(out, session_.repeater().localiser().node_spacing_m(), tile_seq, guidance_, route_status_);
  publisher_->set(guidance_);
  publisher_->set(route_status_);
  return r.eq5;
}

void RouteRepeat::hold(bool in_repeat, bool no_fix_possible, std::uint32_t tile_seq) noexcept {
  if (in_repeat && no_fix_possible) {
    route_status_.status = qc::GuidanceState::kHoldCourse;
    route_status_.side = qc::SideOfRoute::kUnknown;
    route_status_.cross_track_sigma_m = qc::kCrossTrackSigmaMaxM;
    publisher_->set(route_status_);
  }
  if (!in_repeat) {
    route_status_ = qc::RouteStatus{};
    route_status_.tile_seq = static_cast<std::uint16_t>(tile_seq & 0xFFFF);
    publisher_->set(route_status_);
  }
}

void RouteRepeat::forget(std::uint32_t tile_seq) noexcept {
  guidance_ = qc::RouteGuidance{};
  route_status_ = qc::RouteStatus{};
  route_status_.status = qc::GuidanceState::kHoldCourse;
  route_status_.tile_seq = static_cast<std::uint16_t>(tile_seq & 0xFFFF);
  publisher_->set(guidance_);
  publisher_->set(route_status_);
}

}  // namespace qnav::daemon
