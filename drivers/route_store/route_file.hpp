// The route store: route files on a hal::FileStore (format: nav/route/route_format.hpp), the same
// code in qnavd, the qnav tool (firmware/tools/route_file.hpp binds it to the host's file system)
// and a LEON build (hal/sim MemoryFileStore or a flash driver behind the same interface).
//  - RouteFileWriter: append-only and durable node by node. create() writes the header, fsyncs the
//    file and its directory; append() writes one CRC'd record at header + i * record_bytes with
//    pwrite and fdatasync()s it before returning, so a crash or power cut loses at most the node in
//    progress. open_append() reopens a route after a crash: a torn tail (a partial last record) is
//    reported and cut off, the last complete record is CRC-checked, and appending continues.
//  - RouteFileReader (a nav NodeSource): validates the header, counts complete records, reports a
//    torn tail, and reads any node with one pread into a single record buffer (fixed memory whatever
//    the route length; 10,000+ node routes are read through nav/route's NodeWindow). A damaged
//    record is reported (kCorrupt + counter), never half-read.
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

struct RouteWriterOptions {
  bool overwrite = false;       // create(): replace an existing file
  bool sync_each_node = true;   // fdatasync after every record (the durability guarantee)
};

struct RouteAppendReport {
  std::uint32_t nodes = 0;         // complete, valid records found
  std::uint64_t torn_bytes = 0;    // bytes of a partial record cut off the end
};

class RouteFileWriter {
 public:
  explicit RouteFileWriter(hal::FileStore& store) noexcept : store_(store) {}
  RouteFileWriter(const RouteFileWriter&) = delete;
  RouteFileWriter& operator=(const RouteFileWriter&) = delete;
  ~RouteFileWriter();

  Status create(const char* path, const route::RouteParams& params, const RouteWriterOptions& options = RouteWriterOptions{});
  Status open_append(const char* path, RouteAppendReport* report, const RouteWriterOptions& options = RouteWriterOptions{});
  // Appends `node` as record node_count() (its meta.index is set to that).
  Status append(const route::RouteNode& node);
  Status close();
  // Closes (fsync) and renames the file to final_path (atomically replacing a route there), then
  // fsyncs the directory: a route taught under a temporary name becomes the route only when complete.
  Status commit_as(const char* final_path);
  // Capacity for records of up to `bytes` (create/open_append then allocate nothing).
  void reserve(std::size_t bytes) { record_.reserve(bytes); }
  std::uint32_t node_count() const noexcept { return count_; }
  const route::RouteParams& params() const noexcept { return params_; }

 private:
  hal::FileStore& store_;
  int fd_ = -1;
  char path_[512] = {};
  route::RouteParams params_{};
  RouteWriterOptions options_{};
  std::uint32_t count_ = 0;
  std::vector<std::uint8_t> record_;
};

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
  std::uint32_t node_count() const noexcept override { return count_; }
  std::uint64_t torn_bytes() const noexcept { return torn_bytes_; }
  Status load(std::uint32_t index, route::RouteNode& out) noexcept override;
  Status load_meta(std::uint32_t index, route::NodeMeta& out) noexcept;
  // Every node's metadata in order (CRC-checked). Stops at the first damaged record and returns its
  // status; *first_bad (if given) is its index (node_count() when all are good).
  Status read_all_meta(std::vector<route::NodeMeta>& out, std::uint32_t* first_bad);
  const route::RouteFormatCounters& counters() const noexcept { return counters_; }

 private:
  Status read_record(std::uint32_t index) noexcept;
  hal::FileStore& store_;
  int fd_ = -1;
  route::RouteParams params_{};
  std::uint32_t count_ = 0;
  std::uint64_t torn_bytes_ = 0;
  std::vector<std::uint8_t> record_;
  route::RouteFormatCounters counters_;
};

}  // namespace qnav::drivers::route_store
