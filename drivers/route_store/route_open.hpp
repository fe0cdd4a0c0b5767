// The one route-open policy for repeating a taught route: qnavd's Repeat mode and `qnav route
// repeat` / `eval` call this, so a route file is judged the same way on the vehicle and on the bench.
//  - the file must open (header checked): else kMissing (no such file), kStorage (the store failed),
//    kUnreadable (damaged header, wrong format);
//  - a route cut off (no end mark) or with a torn tail is still used: every complete node is checked,
//    and the report says so (cut_off, torn_bytes) for the caller to warn;
//  - more nodes than the caller can hold (max_nodes): kTooLong;
//  - every node's record is checked in full (CRC, magic, index, fields). A damaged node k with at
//    least 2 good nodes before it: the repeat runs on the good prefix 0..k-1 (kGoodPrefix: nodes_used,
//    nodes_unused, why), the reader limited to it; the prefix keeps the filter's node spacing and
//    along-track distances those of a contiguous run of nodes. Fewer than 2 good nodes: kDamaged;
//  - fewer than 2 nodes in all: kTooShort.
// Nothing learnt is lost: the good part of a damaged route is still flown, and the caller raises the
// route-damaged fault so the operator knows.
// Memory: meta takes at most max(node count, its capacity) entries (reserve it to max_nodes first and
// it does not allocate). Time: one read of every node's record.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "drivers/route_store/route_file.hpp"
#include "nav/core/status.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::drivers::route_store {

enum class RepeatOpen : std::uint8_t { kOk, kGoodPrefix, kMissing, kStorage, kUnreadable, kTooLong, kDamaged, kTooShort };
const char* to_string(RepeatOpen o) noexcept;
// kOk and kGoodPrefix: the reader and meta are ready to repeat.
constexpr bool usable(RepeatOpen o) noexcept { return o == RepeatOpen::kOk || o == RepeatOpen::kGoodPrefix; }

struct RepeatOpenReport {
  RepeatOpen outcome = RepeatOpen::kUnreadable;
  Status why;                        // the check that failed (open, first damaged node), ok otherwise
  bool cut_off = false;              // no end mark: the teach did not close the route
  std::uint64_t torn_bytes = 0;      // bytes of a partial node after the last complete one (dropped)
  std::uint32_t file_nodes = 0;      // complete node records in the file
  std::uint32_t first_bad_node = 0;  // kGoodPrefix / kDamaged: the first damaged node
  std::uint32_t nodes_used = 0;      // usable: the nodes the repeat runs on
};

RepeatOpenReport open_route_for_repeat(RouteFileReader& reader, const char* path, std::vector<route::NodeMeta>& meta,
                                       std::size_t max_nodes);

}  // namespace qnav::drivers::route_store
