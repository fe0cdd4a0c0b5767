#include "firmware/tools/map_file.hpp"

#include "hal/linux/posix_file_store.hpp"

namespace qnav::tools {

Status save_map(const char* path, const topo::TopoMap& map, bool metric) noexcept {
  return drivers::map_store::save_map(hal::host_file_store(), path, map, metric);
}
Status load_map(const char* path, topo::TopoMap& map, MapFileInfo* info) noexcept {
  return drivers::map_store::load_map(hal::host_file_store(), path, map, info);
}
Status read_map_header(const char* path, topo::MapHeader& out) noexcept {
  return drivers::map_store::read_map_header(hal::host_file_store(), path, out);
}

}  // namespace qnav::tools
