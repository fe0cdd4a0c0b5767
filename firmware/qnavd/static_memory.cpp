#include "firmware/qnavd/static_memory.hpp"

#include <cstring>

namespace qnav::daemon {

Result<Span<std::byte>> StaticMemory::take(const char* name) noexcept {
  for (std::size_t i = 0; i < table_.buffer_count; ++i) {
    const BufferSpec& b = table_.buffers[i];
    if (std::strcmp(b.name, name) != 0) continue;
    if (b.kind != BufferKind::kStatic) return error(name, "is not a static buffer in the deployment table");
    if (taken_[i]) return error(name, "was taken twice from the static block");
    if (!block_.valid()) return error(name, "static block not allocated (out of memory)");
    void* p = block_.allocate_bytes(b.bytes, alignof(std::max_align_t));
    if (p == nullptr) return error(name, "does not fit in the static block");
    taken_[i] = true;
    ++taken_count_;
    return Span<std::byte>(static_cast<std::byte*>(p), b.bytes);
  }
  return error(name, "is not in the deployment table");
}

Status StaticMemory::complete() noexcept {
  if (!block_.valid() && table_.total_static_bytes() > 0) return error("(block)", "static block not allocated (out of memory)");
  for (std::size_t i = 0; i < table_.buffer_count; ++i)
    if (table_.buffers[i].kind == BufferKind::kStatic && !taken_[i])
      return error(table_.buffers[i].name, "is in the deployment table but start-up did not take it");
  return Status::ok();
}

}  // namespace qnav::daemon
