// Counting replacements of the global allocation functions. See alloc_guard.hpp.
#include "test/support/alloc_guard.hpp"

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <new>

namespace {
// size_t, not uint64_t: 32-bit targets such as LEON3 have no lock-free 64-bit atomics.
std::atomic<std::size_t> g_news{0};
std::atomic<std::size_t> g_deletes{0};
std::atomic<std::size_t> g_mallocs{0};
std::atomic<std::size_t> g_frees{0};
std::atomic<std::size_t> g_new_bytes{0};     // bytes asked of operator new (every form)
std::atomic<std::size_t> g_watch_size{0};    // watch_new_size(): count the news of exactly this size
std::atomic<std::size_t> g_watch_hits{0};
void count_new(std::size_t n) noexcept {
  g_news.fetch_add(1, std::memory_order_relaxed);
  g_new_bytes.fetch_add(n, std::memory_order_relaxed);
  const std::size_t w = g_watch_size.load(std::memory_order_relaxed);
  if (w != 0 && n == w) g_watch_hits.fetch_add(1, std::memory_order_relaxed);
}

void* counted_new(std::size_t n) {
  count_new(n);
  // With malloc counting on, this malloc would count twice; undo that so one new == one count.
#if defined(QNAV_COUNT_MALLOC)
  g_mallocs.fetch_sub(1, std::memory_order_relaxed);
#endif
  void* p = std::malloc(n == 0 ? 1 : n);
  return p;
}
void* counted_new_aligned(std::size_t n, std::align_val_t al) {
  count_new(n);  // posix_memalign is not itself counted
  const std::size_t a = static_cast<std::size_t>(al) < sizeof(void*) ? sizeof(void*) : static_cast<std::size_t>(al);
  void* p = nullptr;
  if (posix_memalign(&p, a, n == 0 ? a : n) != 0) return nullptr;
  return p;
}
void counted_delete(void* p) noexcept {
  if (p == nullptr) return;
  g_deletes.fetch_add(1, std::memory_order_relaxed);
#if defined(QNAV_COUNT_MALLOC)
  g_frees.fetch_sub(1, std::memory_order_relaxed);  // the free() below counts it again
#endif
  std::free(p);
}
}  // namespace

// ---- operator new / delete, every replaceable form --------------------------------------------
void* operator new(std::size_t n) {
  void* p = counted_new(n);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](std::size_t n) {
  void* p = counted_new(n);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return counted_new(n); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return counted_new(n); }
void* operator new(std::size_t n, std::align_val_t al) {
  void* p = counted_new_aligned(n, al);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](std::size_t n, std::align_val_t al) {
  void* p = counted_new_aligned(n, al);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new(std::size_t n, std::align_val_t al, const std::nothrow_t&) noexcept {
  return counted_new_aligned(n, al);
}
void* operator new[](std::size_t n, std::align_val_t al, const std::nothrow_t&) noexcept {
  return counted_new_aligned(n, al);
}
void operator delete(void* p) noexcept { counted_delete(p); }
void operator delete[](void* p) noexcept { counted_delete(p); }
void operator delete(void* p, std::size_t) noexcept { counted_delete(p); }
void operator delete[](void* p, std::size_t) noexcept { counted_delete(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { counted_delete(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { counted_delete(p); }
void operator delete(void* p, std::align_val_t) noexcept { counted_delete(p); }
void operator delete[](void* p, std::align_val_t) noexcept { counted_delete(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { counted_delete(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { counted_delete(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { counted_delete(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { counted_delete(p); }

// ---- malloc family (dynamic glibc only) ---------------------------------------------------------
#if defined(QNAV_COUNT_MALLOC)
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t n) {
  g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(n);
}
void* calloc(std::size_t a, std::size_t b) {
  g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(a, b);
}
void* realloc(void* p, std::size_t n) {
  g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, n);
}
void free(void* p) {
  if (p != nullptr) g_frees.fetch_add(1, std::memory_order_relaxed);
  __libc_free(p);
}
}
#endif

namespace qnav::test {

AllocationCounts allocation_counts() noexcept {
  AllocationCounts c;
  c.news = g_news.load(std::memory_order_relaxed);
  c.deletes = g_deletes.load(std::memory_order_relaxed);
  c.mallocs = g_mallocs.load(std::memory_order_relaxed);
  c.frees = g_frees.load(std::memory_order_relaxed);
  return c;
}

bool malloc_counted() noexcept {
#if defined(QNAV_COUNT_MALLOC)
  return true;
#else
  return false;
#endif
}

std::uint64_t AllocationGuard::allocations() const noexcept {
  const AllocationCounts now = allocation_counts();
  return (now.news - start_.news) + (now.mallocs - start_.mallocs);
}

std::uint64_t AllocationGuard::deallocations() const noexcept {
  const AllocationCounts now = allocation_counts();
  return (now.deletes - start_.deletes) + (now.frees - start_.frees);
}

std::string AllocationGuard::report() const {
  const AllocationCounts now = allocation_counts();
  char buf[160];
  std::snprintf(buf, sizeof buf, "operator new: %llu, malloc-family: %llu%s",
                static_cast<unsigned long long>(now.news - start_.news),
                static_cast<unsigned long long>(now.mallocs - start_.mallocs),
                malloc_counted() ? "" : " (malloc not counted in this build)");
  return buf;
}

}  // namespace qnav::test

namespace qnav::test {
std::size_t new_bytes() noexcept { return g_new_bytes.load(std::memory_order_relaxed); }
void watch_new_size(std::size_t n) noexcept {
  g_watch_hits.store(0, std::memory_order_relaxed);
  g_watch_size.store(n, std::memory_order_relaxed);
}
std::size_t watched_new_count() noexcept { return g_watch_hits.load(std::memory_order_relaxed); }
}  // namespace qnav::test
