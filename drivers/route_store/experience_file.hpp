// ExperienceFile: a route's experiences (nav/route/experience.hpp: format, index) on a hal::FileStore,
// in the companion file ROUTE.exp (experience_path()). The route file itself is not touched: route
// readers of every version ignore the companion, and a route without one has no experiences.
//  - open_read(): for a repeat. Checks the header and its binding to the route (header + node 0 CRC:
//    a companion left from an earlier teach of the same path is refused, kInvalidArgument +
//    other_route), then reads every complete record in full (CRC, magic, record number, fields) into
//    the caller's ExperienceIndex; a damaged record is counted and skipped (an experience is extra
//    knowledge: the route stays usable without it); a torn tail (a partial last record: the learner
//    lost power mid-append) is reported and ignored.
//  - open_append(): for a repeat that learns. The same, then a torn tail is cut off (truncate +
//    fsync, before the first append) and reported; a missing companion is created (header written,
//    file and directory fsync'ed); one shorter than its header (a power cut while creating it: no
//    record can be in it) is rewritten; one bound to another route is moved aside to ROUTE.exp.stale
//    (replacing an older .stale) and a new one is created (report->moved_stale).
//  - Compaction (open_append, before the first append): records are never rewritten in place, so a
//    slot that is replaced (the keep rule, ExperienceIndex::choose_slot) leaves its old record dead
//    in the file. Rule: when the dead records (replaced, or damaged) are at least as many as the live
//    ones and at least compact_min_dead() (default kCompactMinDead = 16), the file is rewritten with
//    the live records only, in their order, renumbered 0.. (the keep rule's "oldest" is unchanged):
//    written to ROUTE.exp.new (created or truncated), fsync'ed, then renamed over ROUTE.exp (the
//    rename makes the name durable). A power cut at any moment leaves at ROUTE.exp either the old
//    file or the compacted one, whole; a leftover ROUTE.exp.new is never read and is overwritten by
//    the next compaction. A compaction that fails (disk full) leaves the old file in use and is
//    reported (compact_failed); learning goes on appending to it. So the file holds at most
//    max(2 x live, live + 16) records plus what the passes since the last open appended.
//  - append(): one record at header + record * record_bytes, fdatasync'ed before it returns, then
//    entered in the index (later records replace earlier ones in the same slot). A power cut loses
//    at most the experience in progress; every fully written one is read back.
//  - As a NodeSource (index = record number): load() decodes an experience's keypoints for the
//    localiser's experience window (node.meta.index = the experience's node).
// Memory: one record buffer (sized at open; reserve() sizes it earlier). Time: open reads every
// record once; append is one write + fdatasync; load one pread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "hal/core/file_store.hpp"
#include "nav/core/status.hpp"
#include "nav/route/experience.hpp"
#include "nav/route/node_window.hpp"

namespace qnav::drivers::route_store {

constexpr std::size_t kExperiencePathBytes = 528;

// ROUTE.exp into out (false when it does not fit).
bool experience_path(const char* route_path, char (&out)[kExperiencePathBytes]) noexcept;

struct RouteIdentity {
  route::RouteParams params{};
  std::uint32_t node_count = 0;
  std::uint32_t header_crc = 0;  // route::route_binding
  std::uint32_t node0_crc = 0;
};
// The binding of a route from its header and node 0. scratch / scratch_bytes (>= the route's record
// size) are the caller's, so this allocates nothing.
Status route_identity(const route::RouteParams& params, route::NodeSource& nodes, route::RouteNode& scratch, Span<std::uint8_t> scratch_bytes,
                      RouteIdentity& out);

struct ExperienceOpenReport {
  bool created = false;        // open_append: there was no companion; a new one was created
  bool moved_stale = false;    // open_append: a companion of another route was moved to ROUTE.exp.stale
  std::uint32_t records = 0;   // complete records in the file
  std::uint32_t damaged = 0;   // of them, refused by their checks (skipped)
  std::uint32_t first_damaged = 0;
  std::uint64_t torn_bytes = 0;  // partial record after the last complete one (ignored; cut by open_append)
  std::uint32_t live = 0;      // experiences in the index afterwards
  bool compacted = false;      // open_append rewrote the file with its live records (records: afterwards)
  bool compact_failed = false; // it tried and could not (the old file is used; compact_status says why)
  std::uint32_t dropped = 0;   // records the compaction dropped (replaced or damaged)
  Status compact_status;
};

class ExperienceFile final : public route::NodeSource {
 public:
  explicit ExperienceFile(hal::FileStore& store) noexcept : store_(store), counters_(route::kExperienceFormatCounterNames) {}
  ExperienceFile(const ExperienceFile&) = delete;
  ExperienceFile& operator=(const ExperienceFile&) = delete;
  ~ExperienceFile();

  // index is reset to the route's node count and filled; its per_node() must be >= the file's
  // max_per_node (records of slots beyond it are refused as damaged otherwise).
  Status open_read(const char* path, const RouteIdentity& route, route::ExperienceIndex& index, ExperienceOpenReport* report = nullptr);
  // per_node: max_per_node written into a new file (an existing file keeps its own).
  Status open_append(const char* path, const RouteIdentity& route, std::uint16_t per_node, route::ExperienceIndex& index,
                     ExperienceOpenReport* report = nullptr, bool sync_each = true);
  // Appends e (its meta.record is set to the record number) durably and enters it in `index`.
  Status append(route::Experience& e, route::ExperienceIndex& index);
  void close();
  void reserve(std::size_t bytes) { record_.reserve(bytes); }
  static constexpr std::uint32_t kCompactMinDead = 16;
  // The compaction rule's minimum of dead records (0xFFFFFFFF: never compact).
  void set_compact_min_dead(std::uint32_t n) noexcept { compact_min_dead_ = n; }
  std::uint32_t compact_min_dead() const noexcept { return compact_min_dead_; }

  std::uint32_t node_count() const noexcept override { return records_; }  // records (the NodeSource's index space)
  Status load(std::uint32_t record, route::RouteNode& out) noexcept override;
  Status load_meta(std::uint32_t record, route::ExperienceMeta& out) noexcept;
  std::uint32_t records() const noexcept { return records_; }
  const route::ExperienceHeader& header() const noexcept { return header_; }
  const route::ExperienceFormatCounters& counters() const noexcept { return counters_; }
  bool is_open() const noexcept { return fd_ >= 0; }

 private:
  Status open_common(const char* path, const RouteIdentity& route, route::ExperienceIndex& index, ExperienceOpenReport* report, bool write,
                     std::uint64_t& file_size);
  Status read_record(std::uint32_t record) noexcept;
  Status compact(const char* path, const RouteIdentity& route, route::ExperienceIndex& index, ExperienceOpenReport& report);
  hal::FileStore& store_;
  int fd_ = -1;
  bool sync_each_ = true;
  std::uint32_t compact_min_dead_ = kCompactMinDead;
  bool other_route_ = false;  // the last open_common refused the file as another route's
  route::RouteParams params_{};
  std::uint32_t route_nodes_ = 0;
  route::ExperienceHeader header_{};
  std::uint32_t records_ = 0;
  std::vector<std::uint8_t> record_;
  route::ExperienceFormatCounters counters_;
};

}  // namespace qnav::drivers::route_store
