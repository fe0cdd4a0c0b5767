// runtime.cpp: what a freestanding C++17 program compiled by g++ needs besides the compiler's own
// code generation, with no libc and no libstdc++ linked:
//  - bare_main_entry / bare_report_trap (called from crt0.S)
//  - operator new/delete over the static heap (bump allocation; delete is a no-op, so nothing may
//    rely on memory being reused: nav/ allocates once at init, DESIGN.md)
//  - memcpy, memmove, memset, memcmp, strlen (gcc emits calls to these for copies and
//    initialisation even at -O3; compiled with -fno-builtin -fno-tree-loop-distribute-patterns so the
//    loops below are not turned back into calls to themselves)
//  - the C++ ABI hooks: __cxa_pure_virtual, __cxa_atexit + __dso_handle (static destructors are
//    never run: the program ends by powering off), __cxa_guard_* (single thread; unused with
//    -fno-threadsafe-statics but cheap), abort
//  - libstdc++'s out-of-line error paths (std::__throw_*): with -fno-exceptions the containers still
//    call them on misuse (vector::at, length errors); here they print and power off.
#include <cstdarg>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <new>

#include "bare.hpp"

extern "C" {
extern char __heap_start[];
extern char __heap_end[];
int main();
}

namespace qnav::bare {
namespace {
std::uintptr_t g_heap_next = 0;
std::size_t g_heap_failed = 0;

void* heap_alloc(std::size_t bytes, std::size_t align) noexcept {
  if (g_heap_next == 0) g_heap_next = reinterpret_cast<std::uintptr_t>(__heap_start);
  if (align < 8) align = 8;
  const std::uintptr_t p = (g_heap_next + (align - 1)) & ~static_cast<std::uintptr_t>(align - 1);
  const std::uintptr_t end = reinterpret_cast<std::uintptr_t>(__heap_end);
  if (p > end || bytes > end - p) {
    ++g_heap_failed;
    return nullptr;
  }
  g_heap_next = p + (bytes == 0 ? 1 : bytes);
  return reinterpret_cast<void*>(p);
}
}  // namespace

std::size_t heap_used() noexcept {
  return g_heap_next == 0 ? 0 : g_heap_next - reinterpret_cast<std::uintptr_t>(__heap_start);
}
std::size_t heap_capacity() noexcept {
  return static_cast<std::size_t>(__heap_end - __heap_start);
}
std::size_t heap_failed() noexcept { return g_heap_failed; }

void fail(const char* why) noexcept {
  put_str("\r\nABORT: ");
  put_str(why);
  put_str("\r\n");
  bare_shutdown(134);
}

}  // namespace qnav::bare

using qnav::bare::fail;
using qnav::bare::heap_alloc;

extern "C" int bare_main_entry() {
  const int rc = main();
  qnav::bare::put_str("EXIT ");
  qnav::bare::put_i32(rc);
  qnav::bare::put_str("\r\n");
  return rc;
}

extern "C" void bare_report_trap(std::uint32_t tt, std::uint32_t pc, std::uint32_t npc) {
  qnav::bare::put_str("\r\nTRAP tt=");
  qnav::bare::put_hex32(tt);
  qnav::bare::put_str(" pc=");
  qnav::bare::put_hex32(pc);
  qnav::bare::put_str(" npc=");
  qnav::bare::put_hex32(npc);
  qnav::bare::put_str("\r\n");
  bare_shutdown(135);
}

// ---- operator new / delete ----
void* operator new(std::size_t n) {
  void* p = heap_alloc(n, alignof(std::max_align_t));
  if (p == nullptr) fail("operator new: static heap exhausted");
  return p;
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return heap_alloc(n, alignof(std::max_align_t)); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return heap_alloc(n, alignof(std::max_align_t)); }
void* operator new(std::size_t n, std::align_val_t a) {
  void* p = heap_alloc(n, static_cast<std::size_t>(a));
  if (p == nullptr) fail("operator new: static heap exhausted");
  return p;
}
void* operator new[](std::size_t n, std::align_val_t a) { return operator new(n, a); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return heap_alloc(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return heap_alloc(n, static_cast<std::size_t>(a));
}
void operator delete(void*) noexcept {}
void operator delete[](void*) noexcept {}
void operator delete(void*, std::size_t) noexcept {}
void operator delete[](void*, std::size_t) noexcept {}
void operator delete(void*, std::align_val_t) noexcept {}
void operator delete[](void*, std::align_val_t) noexcept {}
void operator delete(void*, std::size_t, std::align_val_t) noexcept {}
void operator delete[](void*, std::size_t, std::align_val_t) noexcept {}
void operator delete(void*, const std::nothrow_t&) noexcept {}
void operator delete[](void*, const std::nothrow_t&) noexcept {}

const std::nothrow_t std::nothrow{};

// ---- C library subset ----
extern "C" {

// malloc/free for Eigen's dynamic temporaries (level-3 blocking in triangular solves and products);
// the same bump heap, 16-byte aligned; free is a no-op.
void* malloc(std::size_t n) { return heap_alloc(n, 16); }
void* calloc(std::size_t n, std::size_t size) {
  if (size != 0 && n > static_cast<std::size_t>(-1) / size) return nullptr;
  void* p = heap_alloc(n * size, 16);
  if (p != nullptr) std::memset(p, 0, n * size);
  return p;
}
void free(void*) {}

void* memcpy(void* dst, const void* src, std::size_t n) {
  auto* d = static_cast<unsigned char*>(dst);
  const auto* s = static_cast<const unsigned char*>(src);
  if (((reinterpret_cast<std::uintptr_t>(d) | reinterpret_cast<std::uintptr_t>(s)) & 3u) == 0) {
    for (; n >= 4; n -= 4, d += 4, s += 4)
      *reinterpret_cast<std::uint32_t*>(d) = *reinterpret_cast<const std::uint32_t*>(s);
  }
  while (n-- != 0) *d++ = *s++;
  return dst;
}

void* memmove(void* dst, const void* src, std::size_t n) {
  auto* d = static_cast<unsigned char*>(dst);
  const auto* s = static_cast<const unsigned char*>(src);
  if (d == s || n == 0) return dst;
  if (d < s || d >= s + n) return memcpy(dst, src, n);
  while (n-- != 0) d[n] = s[n];
  return dst;
}

void* memset(void* dst, int c, std::size_t n) {
  auto* d = static_cast<unsigned char*>(dst);
  const auto b = static_cast<unsigned char>(c);
  while (n != 0 && (reinterpret_cast<std::uintptr_t>(d) & 3u) != 0) {
    *d++ = b;
    --n;
  }
  const std::uint32_t w = 0x01010101u * b;
  for (; n >= 4; n -= 4, d += 4) *reinterpret_cast<std::uint32_t*>(d) = w;
  while (n-- != 0) *d++ = b;
  return dst;
}

int memcmp(const void* a, const void* b, std::size_t n) {
  const auto* x = static_cast<const unsigned char*>(a);
  const auto* y = static_cast<const unsigned char*>(b);
  for (std::size_t i = 0; i < n; ++i)
    if (x[i] != y[i]) return x[i] < y[i] ? -1 : 1;
  return 0;
}

std::size_t strlen(const char* s) {
  std::size_t n = 0;
  while (s[n] != '\0') ++n;
  return n;
}

[[noreturn]] void abort() { fail("abort()"); }

void* realloc(void* old, std::size_t n) {
  if (old == nullptr) return malloc(n);
  fail("realloc is not supported (no heap reuse)");
}

// newlib's libm wrappers are built with _IEEE_LIBM (no errno); this is for anything that still
// refers to errno through newlib's reentrancy hook.
int* __errno() {
  static int e = 0;
  return &e;
}

// C++ ABI
void __cxa_pure_virtual() { fail("pure virtual call"); }
void* __dso_handle = nullptr;
int __cxa_atexit(void (*)(void*), void*, void*) { return 0; }  // never run: the program powers off
int atexit(void (*)()) { return 0; }
int __cxa_guard_acquire(std::uint64_t* g) { return *reinterpret_cast<unsigned char*>(g) == 0 ? 1 : 0; }
void __cxa_guard_release(std::uint64_t* g) { *reinterpret_cast<unsigned char*>(g) = 1; }
void __cxa_guard_abort(std::uint64_t*) {}

}  // extern "C"

// libstdc++ error paths (declared in <bits/functexcept.h>).
namespace std {
[[noreturn]] void __throw_bad_alloc() { fail("std::bad_alloc"); }
[[noreturn]] void __throw_bad_array_new_length() { fail("std::bad_array_new_length"); }
[[noreturn]] void __throw_length_error(const char* s) { fail(s); }
[[noreturn]] void __throw_out_of_range(const char* s) { fail(s); }
[[noreturn]] void __throw_out_of_range_fmt(const char* s, ...) { fail(s); }
[[noreturn]] void __throw_logic_error(const char* s) { fail(s); }
[[noreturn]] void __throw_invalid_argument(const char* s) { fail(s); }
[[noreturn]] void __throw_bad_function_call() { fail("std::bad_function_call"); }
}  // namespace std
