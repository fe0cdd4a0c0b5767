// The topological map file (format: nav/topo/map_format.hpp) on a hal::FileStore, beside the route
// store (drivers/route_store): the same code in qnavd's map mode, the qnav tool (over hal/linux's
// PosixFileStore; firmware/tools/map_file.hpp adds path-only calls on the host's file system), host
// tests and every target (hal/sim's MemoryFileStore).
//  - save_map(): the whole map, written to PATH.tmp, fdatasync'ed, then renamed over PATH (atomic,
//    the name made durable by the store). A crash or power cut leaves the previous map or the new
//    one, never a mix. The map changes in place as it learns (SOM adaptation, pruning), so it is
//    rewritten rather than appended; qnav map calls this after every frame that created a node
//    (durable as it grows: a power cut loses at most the changes since the last new node). Cost
//    O(file bytes): 64 + 304 per node + 12 per edge (100 nodes: 31 KB).
//  - load_map(): refuses a damaged file with the check that failed (magic, CRC of the header, of a
//    node or an edge record, truncated or trailing bytes, field ranges, an edge to a missing node,
//    a node beyond the map's capacity); on any refusal the map is cleared (never half-loaded).
// No heap: one record buffer on the stack.
#pragma once

#include "hal/core/file_store.hpp"
#include "nav/core/status.hpp"
#include "nav/topo/map_format.hpp"
#include "nav/topo/topo_map.hpp"

namespace qnav::drivers::map_store {

struct MapFileInfo {
  bool metric = false;          // node positions in metres (else mosaic pixels)
  topo::MapHeader header{};     // filled by load_map
};

Status save_map(hal::FileStore& store, const char* path, const topo::TopoMap& map, bool metric) noexcept;
// The map must be init()ed with capacity >= the file's highest node id + 1 and max_edges_per_node
// >= the file's.
Status load_map(hal::FileStore& store, const char* path, topo::TopoMap& map, MapFileInfo* info) noexcept;

// The header alone (capacity, counts) to size a map before load_map.
Status read_map_header(hal::FileStore& store, const char* path, topo::MapHeader& out) noexcept;

}  // namespace qnav::drivers::map_store
