// RouteTeach: Mode = Teach. A finished tile from the tile pipeline becomes the route's next node,
// appended durably (drivers/route_store RouteFileWriter: each node fsync'ed before the next).
// Consumes: enter(route id, node spacing, swath) when the mode is entered; append(node) per finished
//   tile; close() when the mode is left (the worker flushes the tile in progress first).
// Produces: route_<id>.qroute.new while teaching, committed over route_<id>.qroute at close() when it
//   has >= 2 nodes (else kept as .new: nothing taught is deleted); node_count() for NAV_STATUS.
// A node that cannot be made durable (a full disk, a failing medium) ends the route at its last
// durable node (teach_stopped): appending later ones would leave a gap the repeat pass cannot tell
// from the place. The daemon keeps navigating; the route is committed as it is when teaching ends.
// Memory: the writer's record buffer, reserved in init() for the largest node. Time: one append (one
// write + fsync) per tile.
#pragma once

#include <cstdint>

#include "drivers/route_store/route_file.hpp"
#include "firmware/qnavd/components/component.hpp"
#include "hal/core/file_store.hpp"

namespace qnav::daemon {

class RouteTeach {
 public:
  RouteTeach(const NavContext& ctx, hal::FileStore& store) noexcept : ctx_(ctx), writer_(store) {}
  void init();
  ModeReject enter(std::uint16_t route_id, double spacing_m, double swath_m) noexcept;
  bool open() const noexcept { return open_; }
  // Open and not stopped by a failed append: a finished tile is appended.
  bool writing() const noexcept { return open_ && !stopped_; }
  // Appends a node (when writing()); returns the index it was written at.
  std::uint32_t append(const route::RouteNode& node) noexcept;
  // Commits (>= 2 nodes) or keeps the route as .new; logs teach_closed.
  void close() noexcept;
  std::uint32_t node_count() const noexcept { return writer_.node_count(); }
  // Appends and commits that failed, and whether the last commit failed (the exit code says so).
  std::uint32_t errors() const noexcept { return errors_; }
  void count_error() noexcept { ++errors_; }
  bool commit_failed() const noexcept { return commit_failed_; }

 private:
  const NavContext& ctx_;  // the worker's: its log is set in NavWorker::init
  drivers::route_store::RouteFileWriter writer_;
  std::uint16_t route_id_ = 0;
  bool open_ = false;
  bool stopped_ = false;
  bool commit_failed_ = false;
  std::uint32_t errors_ = 0;
};

}  // namespace qnav::daemon
