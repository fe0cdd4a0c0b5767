#include "firmware/qnav/command.hpp"

#include <cstring>

namespace qnav::cli {
namespace {
constexpr int kMaxCommands = 32;
// Function-local static: safe whatever the order of static initialisation across files.
struct Table {
  Command items[kMaxCommands];
  int count = 0;
};
Table& table() noexcept {
  static Table t;
  return t;
}
}  // namespace

bool register_command(const Command& c) noexcept {
  Table& t = table();
  if (t.count >= kMaxCommands || find_command(c.name) != nullptr) return false;
  t.items[t.count++] = c;
  return true;
}

const Command* find_command(const char* name) noexcept {
  Table& t = table();
  for (int i = 0; i < t.count; ++i)
    if (std::strcmp(t.items[i].name, name) == 0) return &t.items[i];
  return nullptr;
}

int command_count() noexcept { return table().count; }
const Command* command_at(int i) noexcept { return (i >= 0 && i < table().count) ? &table().items[i] : nullptr; }

}  // namespace qnav::cli
