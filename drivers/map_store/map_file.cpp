#include "drivers/map_store/map_file.hpp"

#include <cstdio>
#include <cstring>

namespace qnav::drivers::map_store {

namespace {

class Handle {
 public:
  Handle(hal::FileStore& s, int fd) noexcept : s_(s), fd_(fd) {}
  ~Handle() {
    if (fd_ >= 0) s_.close(fd_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  int fd() const noexcept { return fd_; }

 private:
  hal::FileStore& s_;
  int fd_;
};

}  // namespace

Status save_map(hal::FileStore& store, const char* path, const topo::TopoMap& map, bool metric) noexcept {
  if (!map.ready()) return Status(StatusCode::kNotReady, "map file: map not initialised");
  char tmp[512];
  if (std::snprintf(tmp, sizeof tmp, "%s.tmp", path) >= static_cast<int>(sizeof tmp))
    return Status(StatusCode::kInvalidArgument, "map file: path too long");
  topo::MapHeader h;
  h.max_edges_per_node = static_cast<std::uint16_t>(map.config().max_edges_per_node);
  h.node_count = static_cast<std::uint32_t>(map.node_count());
  h.edge_count = static_cast<std::uint32_t>(map.edge_count());
  h.capacity = static_cast<std::uint32_t>(map.capacity());
  h.observations = map.observations();
  h.revisits = map.revisits();
  h.node_spacing = map.config().node_spacing;
  h.metric = metric;
  std::uint8_t rec[topo::kMapNodeBytes];
  QNAV_RETURN_IF_ERROR(topo::encode_map_header(h, Span<std::uint8_t>(rec, topo::kMapHeaderBytes)));
  Result<int> fd = store.open(tmp, hal::FileMode::kCreateOrTruncate);
  if (!fd) return fd.status();
  {
    Handle handle(store, *fd);
    std::uint64_t at = 0;
    QNAV_RETURN_IF_ERROR(store.write_at(*fd, rec, topo::kMapHeaderBytes, at));
    at += topo::kMapHeaderBytes;
    for (std::size_t i = 0; i < map.capacity(); ++i) {
      const auto id = static_cast<std::uint16_t>(i);
      if (!map.active(id)) continue;
      QNAV_RETURN_IF_ERROR(topo::encode_map_node(id, map.node(id), Span<std::uint8_t>(rec, topo::kMapNodeBytes)));
      QNAV_RETURN_IF_ERROR(store.write_at(*fd, rec, topo::kMapNodeBytes, at));
      at += topo::kMapNodeBytes;
    }
    for (std::size_t i = 0; i < map.capacity(); ++i) {
      const auto a = static_cast<std::uint16_t>(i);
      if (!map.active(a)) continue;
      for (const topo::TopoEdge& e : map.edges(a)) {
        if (e.to <= a) continue;
        QNAV_RETURN_IF_ERROR(topo::encode_map_edge(a, e.to, e.age, Span<std::uint8_t>(rec, topo::kMapEdgeBytes)));
        QNAV_RETURN_IF_ERROR(store.write_at(*fd, rec, topo::kMapEdgeBytes, at));
        at += topo::kMapEdgeBytes;
      }
    }
    QNAV_RETURN_IF_ERROR(store.sync(*fd));
  }
  return store.rename(tmp, path);
}

Status read_map_header(hal::FileStore& store, const char* path, topo::MapHeader& out) noexcept {
  Result<int> fd = store.open(path, hal::FileMode::kRead);
  if (!fd) return fd.status();
  Handle handle(store, *fd);
  Result<std::uint64_t> size = store.size(*fd);
  if (!size) return size.status();
  if (*size < topo::kMapHeaderBytes) return Status(StatusCode::kTruncated, "map file shorter than its header");
  std::uint8_t b[topo::kMapHeaderBytes];
  QNAV_RETURN_IF_ERROR(store.read_at(*fd, b, sizeof b, 0));
  QNAV_RETURN_IF_ERROR(topo::decode_map_header(Span<const std::uint8_t>(b, sizeof b), out));
  const std::uint64_t want = topo::map_file_bytes(out.node_count, out.edge_count);
  if (*size < want) return Status(StatusCode::kTruncated, "map file shorter than its header's node and edge counts");
  if (*size > want) return Status(StatusCode::kCorrupt, "map file has bytes after its last edge");
  return Status::ok();
}

Status load_map(hal::FileStore& store, const char* path, topo::TopoMap& map, MapFileInfo* info) noexcept {
  if (!map.ready()) return Status(StatusCode::kNotReady, "map file: map not initialised");
  map.clear();
  topo::MapHeader h;
  QNAV_RETURN_IF_ERROR(read_map_header(store, path, h));
  if (h.node_count > map.capacity() || h.max_edges_per_node > map.config().max_edges_per_node)
    return Status(StatusCode::kCapacityExceeded, "map file: more nodes or edges per node than this map holds");
  Result<int> fd = store.open(path, hal::FileMode::kRead);
  if (!fd) return fd.status();
  Handle handle(store, *fd);
  auto fail = [&map](Status s) {
    map.clear();
    return s;
  };
  std::uint8_t rec[topo::kMapNodeBytes];
  std::uint64_t at = topo::kMapHeaderBytes;
  int last_id = -1;
  for (std::uint32_t i = 0; i < h.node_count; ++i, at += topo::kMapNodeBytes) {
    Status s = store.read_at(*fd, rec, topo::kMapNodeBytes, at);
    std::uint16_t id = 0;
    topo::TopoNode n;
    if (s) s = topo::decode_map_node(Span<const std::uint8_t>(rec, topo::kMapNodeBytes), id, n);
    if (s && static_cast<int>(id) <= last_id) s = Status(StatusCode::kCorrupt, "map node ids not increasing");
    if (s) s = map.restore_node(id, n);
    if (!s) return fail(s);
    last_id = id;
  }
  for (std::uint32_t i = 0; i < h.edge_count; ++i, at += topo::kMapEdgeBytes) {
    std::uint16_t a = 0, b = 0, age = 0;
    Status s = store.read_at(*fd, rec, topo::kMapEdgeBytes, at);
    if (s) s = topo::decode_map_edge(Span<const std::uint8_t>(rec, topo::kMapEdgeBytes), a, b, age);
    if (s) s = map.restore_edge(a, b, age);
    if (!s) return fail(s);
  }
  map.restore_progress(h.observations, h.revisits);
  if (info != nullptr) {
    info->metric = h.metric;
    info->header = h;
  }
  return Status::ok();
}

}  // namespace qnav::drivers::map_store
