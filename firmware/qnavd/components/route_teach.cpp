#include "firmware/qnavd/components/route_teach.hpp"

#include "firmware/pipeline/route_defaults.hpp"

namespace qnav::daemon {

void RouteTeach::init() { writer_.reserve(route::record_bytes(route::kMaxKeypointsPerNode)); }

ModeReject RouteTeach::enter(std::uint16_t route_id, double spacing_m, double swath_m) noexcept {
  char final_path[1024];
  route_file_path(*ctx_.cfg, route_id, "", final_path, sizeof final_path);
  // Taught under route_<id>.qroute.new and committed over route_<id>.qroute when the teach ends (the
  // old route stays whole until then). A run that was cut off (power, kill -9) or too short to commit
  // left its nodes under .new: the route store moves them aside to .new.kept.<n>, never deletes them.
  drivers::route_store::RouteWriterOptions o;
  o.replace_existing = true;
  drivers::route_store::RouteReplaceReport rep;
  const route::RouteParams params = pipeline::side_scan_route_params(ctx_.cfg->tiles, spacing_m, swath_m);
  const Status s = writer_.create_replacement(final_path, params, o, &rep);
  if (rep.previous_kept && ctx_.log) std::fprintf(ctx_.log, "{\"event\":\"teach_previous_kept\",\"file\":\"%s\"}\n", rep.kept_path);
  if (!s) {
    if (ctx_.log) std::fprintf(ctx_.log, "{\"event\":\"error\",\"what\":\"teach: %s.new: %s\"}\n", final_path, s.message());
    return ModeReject::kStorage;
  }
  route_id_ = route_id;
  open_ = true;
  stopped_ = false;
  return ModeReject::kNone;
}

std::uint32_t RouteTeach::append(const route::RouteNode& node) noexcept {
  const std::uint32_t index = writer_.node_count();
  if (!open_ || stopped_) return index;
  const Status s = writer_.append(node);
  if (!s) {
    ++errors_;
    stopped_ = true;
    if (ctx_.log)
      std::fprintf(ctx_.log, "{\"event\":\"teach_stopped\",\"route_id\":%u,\"nodes_durable\":%u,\"why\":\"%s\"}\n", route_id_,
                   writer_.node_count(), s.message());
  }
  return index;
}

void RouteTeach::close() noexcept {
  if (!open_) return;
  char final_path[1024];
  route_file_path(*ctx_.cfg, route_id_, "", final_path, sizeof final_path);
  const std::uint32_t nodes = writer_.node_count();
  // Too short to repeat: kept as .new, nothing taught is deleted.
  const Status s = nodes >= 2 ? writer_.commit_as(final_path) : writer_.close();
  if (ctx_.log)
    std::fprintf(ctx_.log, "{\"event\":\"teach_closed\",\"route_id\":%u,\"nodes\":%u,\"file\":\"%s%s\",\"ok\":%s,\"why\":\"%s\"}\n", route_id_, nodes,
                 final_path, nodes >= 2 ? "" : ".new", s ? "true" : "false", s ? "" : s.message());
  if (!s) {
    commit_failed_ = true;
    ++errors_;
  }
  open_ = false;
}

}  // namespace qnav::daemon
