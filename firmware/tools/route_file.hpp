// The route store on this host's file system: drivers/route_store's RouteFileWriter / RouteFileReader
// bound to hal/linux's PosixFileStore, for the qnav tool and host tests. qnavd passes its own
// FileStore to the drivers/route_store classes directly.
#pragma once

#include "drivers/route_store/route_file.hpp"
#include "hal/linux/posix_file_store.hpp"

namespace qnav::tools {

using drivers::route_store::kRoutePathBytes;
using drivers::route_store::RouteAppendReport;
using drivers::route_store::RouteEnd;
using drivers::route_store::RouteReplaceReport;
using drivers::route_store::RouteWriterOptions;

class RouteFileWriter final : public drivers::route_store::RouteFileWriter {
 public:
  RouteFileWriter() noexcept : drivers::route_store::RouteFileWriter(hal::host_file_store()) {}
};

class RouteFileReader final : public drivers::route_store::RouteFileReader {
 public:
  RouteFileReader() noexcept : drivers::route_store::RouteFileReader(hal::host_file_store()) {}
};

}  // namespace qnav::tools
