#include "firmware/qnavd/components/component.hpp"

namespace qnav::daemon {

const char* to_string(ModeReject r) noexcept {
  switch (r) {
    case ModeReject::kNone: return "none";
    case ModeReject::kUnsupportedMode: return "mode not supported by this build";
    case ModeReject::kRouteMissing: return "route file not found";
    case ModeReject::kRouteDamaged: return "route file damaged";
    case ModeReject::kRouteTooShort: return "route has fewer than 2 nodes";
    case ModeReject::kStorage: return "route storage error";
    case ModeReject::kNoHeading: return "no recent attitude (heading)";
    case ModeReject::kRouteTooLong: return "route has more nodes than route.max_nodes";
    case ModeReject::kRouteMismatch: return "route does not fit this configuration (sensor or geometry)";
  }
  return "?";
}

Result<Arena*> StageArena::take(StaticMemory* mem, const char* name, std::size_t bytes) {
  if (mem != nullptr) {
    Result<Span<std::byte>> r = mem->take(name);
    if (!r) return r.status();
    view = std::make_unique<Arena>(r.value());
    return view.get();
  }
  own = std::make_unique<ArenaStorage>(bytes);
  if (!own->valid()) return Status(StatusCode::kCapacityExceeded, "nav worker: cannot allocate a stage arena");
  return static_cast<Arena*>(own.get());
}

void route_file_path(const DaemonConfig& cfg, std::uint16_t id, const char* suffix, char* out, std::size_t n) noexcept {
  std::snprintf(out, n, "%s/route_%u.qroute%s", cfg.route_dir.c_str(), static_cast<unsigned>(id), suffix);
}

}  // namespace qnav::daemon
