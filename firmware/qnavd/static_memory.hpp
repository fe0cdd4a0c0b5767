// StaticMemory: the one block of memory qnavd's start-up allocates for every kStatic buffer of its
// deployment table (deployment.hpp), and the only place those buffers come from. take(name) hands
// out exactly the bytes the table gives that buffer, once; a name the table does not list, a second
// take of the same name, or a block smaller than the table (an allocation failure) is an error that
// names the buffer, and start-up fails with it. complete() then checks that every static buffer of
// the table was taken and nothing else: the printed table (`qnavd --print-deployment`) cannot
// disagree with what runs.
// Memory: one allocation of Deployment::total_static_bytes() in the constructor; take() is O(buffers)
// and allocates nothing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>

#include "firmware/qnavd/deployment.hpp"
#include "nav/core/arena.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::daemon {

class StaticMemory {
 public:
  explicit StaticMemory(const Deployment& d) : table_(d), block_(d.total_static_bytes()) {}
  StaticMemory(const StaticMemory&) = delete;
  StaticMemory& operator=(const StaticMemory&) = delete;

  // The bytes of static buffer `name` (aligned to std::max_align_t), or an error naming it.
  Result<Span<std::byte>> take(const char* name) noexcept;
  // The same as n objects of T (default-initialised); the table's bytes must hold them.
  template <typename T>
  Result<Span<T>> take_array(const char* name, std::size_t n) noexcept {
    static_assert(alignof(T) <= alignof(std::max_align_t), "a static buffer is aligned to max_align_t");
    static_assert(std::is_trivially_destructible<T>::value, "static buffers hold trivially destructible types");
    Result<Span<std::byte>> r = take(name);
    if (!r) return r.status();
    if (r.value().size() < n * sizeof(T)) return error(name, "is smaller in the deployment table than its user needs");
    // The block hands out max_align_t-aligned buffers (take()); through void* so that targets with strict
    // alignment (armhf: -Wcast-align) see no alignment-raising cast.
    void* raw = r.value().data();
    T* first = static_cast<T*>(raw);
    for (std::size_t i = 0; i < n; ++i) new (first + i) T{};
    return Span<T>(first, n);
  }
  // Every static buffer of the table was taken (and the block was allocated).
  Status complete() noexcept;

  std::size_t capacity() const noexcept { return block_.capacity(); }
  std::size_t used() const noexcept { return block_.used(); }
  std::size_t taken() const noexcept { return taken_count_; }
  const Deployment& table() const noexcept { return table_; }
  // The buffer a failed call named (for the start-up error message).
  const char* failed_name() const noexcept { return failed_name_; }

 private:
  Status error(const char* name, const char* why) noexcept {
    failed_name_ = name;
    return Status(StatusCode::kCapacityExceeded, why);
  }
  Deployment table_;
  ArenaStorage block_;
  bool taken_[Deployment::kMaxBuffers] = {};
  std::size_t taken_count_ = 0;
  const char* failed_name_ = "";
};

}  // namespace qnav::daemon
