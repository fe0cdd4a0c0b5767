// The route store: route files on a hal::FileStore (format: nav/route/route_format.hpp), the same
// code in qnavd, the qnav tool (firmware/tools/route_file.hpp binds it to the host's file system)
// and a LEON build (hal/sim MemoryFileStore or a flash driver behind the same interface).
//  - RouteFileWriter: append-only and durable node by node. create() writes the header of a new
//    file (never one that exists), fsyncs the file and its directory; append() writes one CRC'd
//    record at header + i * record_bytes and fdatasync()s it before returning, so a crash or power
//    cut loses at most the node in progress. close() appends the end mark ("closed cleanly, N
//    nodes") and fsyncs; a writer destroyed or abandon()ed without close() leaves no mark, so the
//    route reads as cut off. commit_as() closes and renames atomically (directory fsync'ed).
//    create_replacement() is the only way to replace a route: the new one is taught under
//    FINAL.new (a previous run's leftover .new is moved aside to FINAL.new.kept.<n>, nothing taught
//    is deleted) and commit() renames it over FINAL only when complete, so the old route survives
//    any crash before that. open_append() reopens a route after a crash or a close: a torn tail (a
//    partial last record) or the end mark is cut off and reported, the last complete record is
//    checked, and appending continues.
//  - RouteFileReader (a nav NodeSource): validates the header, counts complete records, tells a
//    route closed cleanly (end mark, count agrees) from a cut-off one, reports a torn tail, and
//    reads any node with one pread into a single record buffer (fixed memory whatever the route
//    length; 10,000+ node routes are read through nav/route's NodeWindow). A damaged record is
//    reported (kCorrupt + counter naming the check), never half-read; limit_nodes() keeps a good
//    prefix usable.
// Errors are Status values; the store's failures keep its message (the OS reason on Linux).
// Memory: one record buffer per object, sized at create/open (reserve() sizes it earlier, so a
// daemon opens routes after start-up without allocating). Every target.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "hal/core/file_store.hpp"
#include "nav/core/status.hpp"
#include "nav/route/node_window.hpp"
#include "nav/route/route_format.hpp"

namespace qnav::drivers::route_store {

constexpr std::size_t kRoutePathBytes = 512;

struct RouteWriterOptions {
  bool sync_each_node = true;     // fdatasync after every record (the durability guarantee)
  bool replace_existing = false;  // create_replacement(): may replace a route at the final path
};

struct RouteAppendReport {
  std::uint32_t nodes = 0;          // complete, valid records found
  std::uint64_t torn_bytes = 0;     // bytes of a partial record cut off the end
  bool end_mark_cut = false;        // the route had been closed cleanly: its end mark was cut off
  std::uint16_t version = 0;        // the file's format version (1 stays 1; records are the same)
  bool damaged = false;             // refused: the last complete record (node nodes - 1) is damaged
};

struct RouteReplaceReport {
  bool previous_kept = false;           // a previous run's FINAL.new was moved aside to kept_path
  char kept_path[kRoutePathBytes] = {};
  char temp_path[kRoutePathBytes] = {};  // where the new route is taught until commit()
};

class RouteFileWriter {
 public:
  explicit RouteFileWriter(hal::FileStore& store) noexcept : store_(store) {}
  RouteFileWriter(const RouteFileWriter&) = delete;
  RouteFileWriter& operator=(const RouteFileWriter&) = delete;
  ~RouteFileWriter();  // abandon(): no end mark

  // A new route at path (refused when a file exists there: nothing is ever truncated).
  Status create(const char* path, const route::RouteParams& params, const RouteWriterOptions& options = RouteWriterOptions{});
  // A route that becomes final_path at commit(): taught under final_path + ".new". Refused when
  // final_path exists unless options.replace_existing. A previous run's .new (cut off) is moved
  // aside under the first free final_path + ".new.kept.<n>" (report->previous_kept).
  Status create_replacement(const char* final_path, const route::RouteParams& params, const RouteWriterOptions& options = RouteWriterOptions{},
                            RouteReplaceReport* report = nullptr);
  Status open_append(const char* path, RouteAppendReport* report, const RouteWriterOptions& options = RouteWriterOptions{});
  // Appends `node` as record node_count() (its meta.index is set to that). A node the format would
  // refuse to read back (non-finite or absurd fields) is refused (kInvalidArgument), nothing written.
  Status append(const route::RouteNode& node);
  // Appends the end mark ("closed cleanly, node_count() nodes"), fsyncs and closes. After a failed
  // append, the partial record is cut off first.
  Status close();
  // fsyncs and closes without the end mark: the route reads as cut off (a teach that did not finish).
  Status abandon();
  // close(), then renames the file to final_path (atomically replacing a route there) and fsyncs
  // the directory: a route taught under a temporary name becomes the route only when complete.
  Status commit_as(const char* final_path);
  // commit_as() the final path given to create_replacement().
  Status commit();
  // Capacity for records of up to `bytes` (create/open_append then allocate nothing).
  void reserve(std::size_t bytes) { record_.reserve(bytes); }
  std::uint32_t node_count() const noexcept { return count_; }
  const route::RouteParams& params() const noexcept { return params_; }
  // The file being written (the temporary name after create_replacement()).
  const char* path() const noexcept { return path_; }

 private:
  Status finish(bool mark);
  hal::FileStore& store_;
  int fd_ = -1;
  char path_[kRoutePathBytes] = {};
  char final_path_[kRoutePathBytes] = {};
  route::RouteParams params_{};
  RouteWriterOptions options_{};
  std::uint32_t count_ = 0;
  bool write_failed_ = false;  // an append failed after it may have written part of its record
  std::vector<std::uint8_t> record_;
};

// How a route file ends.
enum class RouteEnd : std::uint8_t {
  kClosedCleanly,    // the end mark, and its node count agrees with the records
  kCutOff,           // version 2 without an end mark: the writer was killed or lost power
  kCountMismatch,    // an end mark whose node count disagrees with the records
  kNoEndMarkV1,      // version 1: written before end marks existed; complete or cut off, unknown
};
const char* to_string(RouteEnd e) noexcept;

class RouteFileReader : public route::NodeSource {
 public:
  explicit RouteFileReader(hal::FileStore& store) noexcept : store_(store), counters_(route::kRouteFormatCounterNames) {}
  RouteFileReader(const RouteFileReader&) = delete;
  RouteFileReader& operator=(const RouteFileReader&) = delete;
  virtual ~RouteFileReader();  // virtual: firmware/tools binds it to the host file system by derivation

  Status open(const char* path);
  void close();
  // Capacity for records of up to `bytes` (open then allocates nothing).
  void reserve(std::size_t bytes) { record_.reserve(bytes); }
  const route::RouteParams& params() const noexcept { return params_; }
  // Nodes served (the file's complete records, or fewer after limit_nodes()).
  std::uint32_t node_count() const noexcept override { return count_; }
  // Complete records in the file.
  std::uint32_t file_nodes() const noexcept { return file_nodes_; }
  // Bytes after the last complete record that are not a valid end mark (a partial node, dropped).
  std::uint64_t torn_bytes() const noexcept { return torn_bytes_; }
  std::uint16_t format_version() const noexcept { return version_; }
  RouteEnd end() const noexcept { return end_; }
  bool closed_cleanly() const noexcept { return end_ == RouteEnd::kClosedCleanly; }
  // The node count the end mark records (0 without one).
  std::uint32_t end_mark_nodes() const noexcept { return end_mark_nodes_; }
  // Serves only nodes 0..n-1 (a good prefix before a damaged node); n <= file_nodes().
  Status limit_nodes(std::uint32_t n) noexcept;
  Status load(std::uint32_t index, route::RouteNode& out) noexcept override;
  Status load_meta(std::uint32_t index, route::NodeMeta& out) noexcept;
  // Every node's metadata in order, each record checked in full (CRC, magic, index, every field,
  // keypoints included). Stops at the first damaged record and returns its status: out then holds
  // the good prefix, *first_bad (if given) is the damaged node's index (node_count() when all are good).
  Status read_all_meta(std::vector<route::NodeMeta>& out, std::uint32_t* first_bad);
  const route::RouteFormatCounters& counters() const noexcept { return counters_; }

 private:
  Status read_record(std::uint32_t index) noexcept;
  hal::FileStore& store_;
  int fd_ = -1;
  route::RouteParams params_{};
  std::uint32_t count_ = 0;
  std::uint32_t file_nodes_ = 0;
  std::uint64_t torn_bytes_ = 0;
  std::uint16_t version_ = 0;
  RouteEnd end_ = RouteEnd::kCutOff;
  std::uint32_t end_mark_nodes_ = 0;
  std::vector<std::uint8_t> record_;
  route::RouteFormatCounters counters_;
};

}  // namespace qnav::drivers::route_store
