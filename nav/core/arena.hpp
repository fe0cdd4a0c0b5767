// Arena: a bump allocator over one block of memory sized once at start-up from the configuration.
// Stages carve their buffers from it in init(); nothing is freed individually; reset() releases all.
// The arena never grows: a request that does not fit returns an empty Span / nullptr and is
// counted in failed_requests(), so a configuration that needs more memory than budgeted fails at
// start-up with a clear error instead of allocating later.
//  - Arena(Span<byte>) works over caller memory (a static array on a bare-metal LEON).
//  - ArenaStorage owns its block: one heap allocation in its constructor, none after.
// allocate: O(1). Objects allocated are default-initialised; the arena never runs destructors, so it
// holds trivially destructible types only (checked at compile time).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav {

class Arena {
 public:
  Arena() noexcept = default;
  explicit Arena(Span<std::byte> block) noexcept : block_(block) {}
  Arena(const Arena&) = delete;
  Arena& operator=(const Arena&) = delete;

  // Raw bytes with the given alignment (a power of two); nullptr when it does not fit.
  void* allocate_bytes(std::size_t bytes, std::size_t align) noexcept {
    if (align == 0 || (align & (align - 1)) != 0) {
      ++failed_;
      return nullptr;
    }
    const std::uintptr_t base = reinterpret_cast<std::uintptr_t>(block_.data());
    const std::uintptr_t cur = base + used_;
    const std::uintptr_t aligned = (cur + (align - 1)) & ~static_cast<std::uintptr_t>(align - 1);
    const std::size_t pad = static_cast<std::size_t>(aligned - cur);
    if (pad > block_.size() - used_ || bytes > block_.size() - used_ - pad) {
      ++failed_;
      return nullptr;
    }
    used_ += pad + bytes;
    if (used_ > high_water_) high_water_ = used_;
    return reinterpret_cast<void*>(aligned);
  }

  // n default-initialised T; an empty Span when it does not fit (or n == 0).
  template <typename T>
  Span<T> allocate(std::size_t n) noexcept {
    static_assert(std::is_trivially_destructible<T>::value, "Arena holds trivially destructible types only");
    if (n == 0 || n > (static_cast<std::size_t>(-1) / sizeof(T))) {
      if (n != 0) ++failed_;
      return Span<T>();
    }
    void* p = allocate_bytes(n * sizeof(T), alignof(T));
    if (p == nullptr) return Span<T>();
    T* first = static_cast<T*>(p);
    for (std::size_t i = 0; i < n; ++i) new (first + i) T{};
    return Span<T>(first, n);
  }

  std::size_t capacity() const noexcept { return block_.size(); }
  std::size_t used() const noexcept { return used_; }
  std::size_t remaining() const noexcept { return block_.size() - used_; }
  std::size_t high_water() const noexcept { return high_water_; }
  std::size_t failed_requests() const noexcept { return failed_; }
  // Forgets every allocation (the memory is reused by the next allocate calls).
  void reset() noexcept { used_ = 0; }

 private:
  Span<std::byte> block_;
  std::size_t used_ = 0;
  std::size_t high_water_ = 0;
  std::size_t failed_ = 0;
};

// An Arena that owns its block (one allocation, at construction).
class ArenaStorage : public Arena {
 public:
  explicit ArenaStorage(std::size_t bytes)
      : ArenaStorage(std::unique_ptr<std::byte[]>(new (std::nothrow) std::byte[bytes]), bytes) {}
  bool valid() const noexcept { return mem_ != nullptr; }

 private:
  ArenaStorage(std::unique_ptr<std::byte[]> mem, std::size_t bytes)
      : Arena(Span<std::byte>(mem.get(), mem ? bytes : 0)), mem_(std::move(mem)) {}
  std::unique_ptr<std::byte[]> mem_;
};

}  // namespace qnav
