// The topological map file on the host's file system, for the tool and host tests: path-only calls
// over hal/linux's PosixFileStore. The file format code is drivers/map_store (what qnavd links).
#pragma once

#include "drivers/map_store/map_file.hpp"

namespace qnav::tools {

using drivers::map_store::load_map;
using drivers::map_store::MapFileInfo;
using drivers::map_store::read_map_header;
using drivers::map_store::save_map;

Status save_map(const char* path, const topo::TopoMap& map, bool metric) noexcept;
Status load_map(const char* path, topo::TopoMap& map, MapFileInfo* info) noexcept;
Status read_map_header(const char* path, topo::MapHeader& out) noexcept;

}  // namespace qnav::tools
