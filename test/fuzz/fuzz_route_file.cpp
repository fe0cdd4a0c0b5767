// Route files (the route store every mode reads): the bytes as a file through
//  - nav/route/route_format: decode_header, then decode_node / decode_node_meta of every whole record;
//  - drivers/route_store on hal/sim's MemoryFileStore: RouteFileReader (open, every node, every meta)
//    and RouteFileWriter::open_append (torn-tail / end-mark recovery) + one append + close, after
//    which the reader must serve exactly one node more than the recovery reported.
// Byte 0 bit 0 repairs the CRCs (header bytes 60..63, each record's last 4 bytes) so the fuzzer gets
// past them to the fields behind; the rest of the input is the file.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "drivers/route_store/route_file.hpp"
#include "hal/sim/memory_file_store.hpp"
#include "nav/core/byte_order.hpp"
#include "nav/core/crc.hpp"
#include "nav/route/route_format.hpp"
#include "test/fuzz/fuzz_support.hpp"
#include "test/support/route_nodes.hpp"

namespace {
using namespace qnav;

constexpr std::size_t kStoreBytes = hal::MemoryFileStore::kMaxFiles * (256u << 10);

std::uint8_t* store_memory() {
  static std::vector<std::uint8_t> m(kStoreBytes);
  return m.data();
}

void repair_crcs(std::vector<std::uint8_t>& f) {
  if (f.size() < route::kHeaderBytes) return;
  store_le_u32(f.data() + 60, crc32(f.data(), 60));
  Result<route::RouteParams> p = route::decode_header(Span<const std::uint8_t>(f.data(), f.size()), nullptr);
  if (!p) return;
  const std::size_t rb = route::record_bytes(p->max_keypoints);
  for (std::size_t off = route::kHeaderBytes; off + rb <= f.size(); off += rb)
    store_le_u32(f.data() + off + rb - 4, crc32(f.data() + off, rb - 4));
}
}  // namespace

int qnav_fuzz_route_file(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const bool repair = (data[0] & 1) != 0;
  std::vector<std::uint8_t> file(data + 1, data + size);
  if (repair) repair_crcs(file);

  // The pure decoders.
  route::RouteFormatCounters counters(route::kRouteFormatCounterNames);
  Result<route::RouteParams> p = route::decode_header(Span<const std::uint8_t>(file.data(), file.size()), &counters);
  static route::RouteNode node;
  if (p) {
    const std::size_t rb = route::record_bytes(p->max_keypoints);
    std::uint32_t i = 0;
    for (std::size_t off = route::kHeaderBytes; off + rb <= file.size(); off += rb, ++i) {
      const Span<const std::uint8_t> rec(file.data() + off, rb);
      if (route::decode_node(p.value(), rec, i, node, &counters).is_ok() && node.keypoints.size() > p->max_keypoints) __builtin_trap();
      route::NodeMeta meta;
      (void)route::decode_node_meta(p.value(), rec, i, meta, &counters);
    }
  }

  // The route store on a memory file system.
  hal::MemoryFileStore store(Span<std::uint8_t>(store_memory(), kStoreBytes));
  if (file.size() > store.file_capacity() / 2) file.resize(store.file_capacity() / 2);
  Result<int> h = store.open("r.qroute", hal::FileMode::kCreateNew);
  if (!h) __builtin_trap();
  if (!file.empty() && !store.write_at(h.value(), file.data(), file.size(), 0)) __builtin_trap();
  store.close(h.value());
  {
    drivers::route_store::RouteFileReader reader(store);
    if (reader.open("r.qroute")) {
      for (std::uint32_t k = 0; k < reader.node_count() && k < 4096; ++k) {
        (void)reader.load(k, node);
        route::NodeMeta meta;
        (void)reader.load_meta(k, meta);
      }
      std::vector<route::NodeMeta> metas;
      std::uint32_t first_bad = 0;
      (void)reader.read_all_meta(metas, &first_bad);
      if (first_bad > reader.node_count()) __builtin_trap();
    }
  }
  drivers::route_store::RouteAppendReport report;
  std::uint32_t appended_as = 0;
  bool appended = false;
  {
    drivers::route_store::RouteFileWriter writer(store);
    if (writer.open_append("r.qroute", &report)) {
      const route::RouteNode n = test::route_node(report.nodes, 3);
      if (writer.append(n).is_ok()) {
        appended = true;
        appended_as = writer.node_count();
      }
      (void)writer.close();
    }
  }
  if (appended) {
    // Recovery + one durable append: a reader sees every node the writer reported, the new one intact.
    drivers::route_store::RouteFileReader reader(store);
    if (!reader.open("r.qroute").is_ok() || reader.node_count() != appended_as) __builtin_trap();
    if (!reader.load(appended_as - 1, node).is_ok() || node.keypoints.size() != 3) __builtin_trap();
  }
  return 0;
}

static void seeds_route_file(qnav::fuzz::Seeds& out) {
  using namespace qnav;
  for (int variant = 0; variant < 3; ++variant) {
    hal::MemoryFileStore store(Span<std::uint8_t>(store_memory(), kStoreBytes));
    {
      drivers::route_store::RouteFileWriter w(store);
      if (!w.create("seed.qroute", test::route_params(variant == 2 ? 1 : 4))) continue;
      for (std::uint32_t i = 0; i < 3; ++i) (void)w.append(test::route_node(i, variant == 2 ? 1 : 3));
      if (variant != 1) (void)w.close();  // variant 1: cut off (no end mark)
    }
    Result<int> h = store.open("seed.qroute", hal::FileMode::kRead);
    if (!h) continue;
    Result<std::uint64_t> n = store.size(h.value());
    std::string bytes(1, '\0');
    if (n) {
      bytes.resize(1 + n.value());
      if (!store.read_at(h.value(), reinterpret_cast<std::uint8_t*>(&bytes[1]), n.value(), 0)) bytes.resize(1);
    }
    store.close(h.value());
    if (bytes.size() > 1) out.push_back(qnav::fuzz::Seed{"route-" + std::to_string(variant), bytes});
  }
  if (!out.empty()) {
    std::string torn = out[0].bytes.substr(0, out[0].bytes.size() - 100);
    torn[0] = 1;  // CRCs repaired: the fields behind them are reached
    out.push_back(qnav::fuzz::Seed{"route-torn-repaired", torn});
  }
}
QNAV_FUZZ_TARGET(route_file, 200)
