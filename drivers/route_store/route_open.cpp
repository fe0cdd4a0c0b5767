#include "drivers/route_store/route_open.hpp"

namespace qnav::drivers::route_store {

const char* to_string(RepeatOpen o) noexcept {
  switch (o) {
    case RepeatOpen::kOk: return "ok";
    case RepeatOpen::kGoodPrefix: return "good prefix";
    case RepeatOpen::kMissing: return "missing";
    case RepeatOpen::kStorage: return "storage error";
    case RepeatOpen::kUnreadable: return "unreadable";
    case RepeatOpen::kTooLong: return "too long";
    case RepeatOpen::kDamaged: return "damaged";
    case RepeatOpen::kTooShort: return "too short";
  }
  return "?";
}

RepeatOpenReport open_route_for_repeat(RouteFileReader& reader, const char* path, std::vector<route::NodeMeta>& meta,
                                       std::size_t max_nodes) {
  RepeatOpenReport r;
  reader.close();
  meta.clear();
  Status s = reader.open(path);
  if (!s) {
    r.why = s;
    r.outcome = s.code() == StatusCode::kNotFound ? RepeatOpen::kMissing : s.code() == StatusCode::kIoError ? RepeatOpen::kStorage : RepeatOpen::kUnreadable;
    return r;
  }
  r.cut_off = !reader.closed_cleanly();
  r.torn_bytes = reader.torn_bytes();
  r.file_nodes = reader.file_nodes();
  if (reader.node_count() > max_nodes) {
    r.outcome = RepeatOpen::kTooLong;
    r.why = Status(StatusCode::kCapacityExceeded, "more nodes than this configuration holds (route.max_nodes)");
    reader.close();
    return r;
  }
  std::uint32_t bad = 0;
  s = reader.read_all_meta(meta, &bad);
  if (!s) {
    r.why = s;
    r.first_bad_node = bad;
    if (bad < 2) {
      r.outcome = RepeatOpen::kDamaged;
      reader.close();
      meta.clear();
      return r;
    }
    const Status ls = reader.limit_nodes(bad);
    if (!ls) {
      r.why = ls;
      r.outcome = RepeatOpen::kDamaged;
      reader.close();
      meta.clear();
      return r;
    }
    r.outcome = RepeatOpen::kGoodPrefix;
    r.nodes_used = bad;
    return r;
  }
  if (meta.size() < 2) {
    r.outcome = RepeatOpen::kTooShort;
    r.why = Status(StatusCode::kInvalidArgument, "a route needs at least 2 nodes");
    reader.close();
    return r;
  }
  r.outcome = RepeatOpen::kOk;
  r.nodes_used = static_cast<std::uint32_t>(meta.size());
  return r;
}

}  // namespace qnav::drivers::route_store
