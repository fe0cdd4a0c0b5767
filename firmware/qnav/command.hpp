// The qnav tool's command table. Each command lives in its own file under commands/ and registers
// itself at static-initialisation time, so adding a command touches no shared file.
//
// A command declares its options on its CLI11 subcommand (QNAV_CLI_COMMAND: the setup function adds
// options and sub-subcommands with firmware/cli/cli_app.hpp and binds each leaf to the function that
// runs it with Runner::on). main.cpp parses strictly (docs/cli.md) and runs the selected leaf.
// Exit codes: 0 success, 1 failure of the work (nothing valid processed included), 2 usage error.
#pragma once

#include <functional>
#include <utility>
#include <vector>

namespace CLI {
class App;
}

namespace qnav::cli {

// The actions bound to subcommands; after a parse, the deepest selected subcommand's action runs.
class Runner {
 public:
  void on(CLI::App* app, std::function<int()> action) { actions_.emplace_back(app, std::move(action)); }
  // The action of app itself, or nullptr.
  const std::function<int()>* find(const CLI::App* app) const {
    for (const auto& a : actions_)
      if (a.first == app) return &a.second;
    return nullptr;
  }

 private:
  std::vector<std::pair<const CLI::App*, std::function<int()>>> actions_;
};

using SetupFn = void (*)(CLI::App& cmd, Runner& run);

struct Command {
  const char* name;     // first word after `qnav`
  const char* summary;  // one line for `qnav --help`
  SetupFn setup;        // declares the command's options and subcommands
};

// Returns false (and the command is not added) when the table is full or the name is taken.
bool register_command(const Command& c) noexcept;
const Command* find_command(const char* name) noexcept;
int command_count() noexcept;
const Command* command_at(int i) noexcept;

}  // namespace qnav::cli

#define QNAV_COMMAND_CAT2(a, b) a##b
#define QNAV_COMMAND_CAT(a, b) QNAV_COMMAND_CAT2(a, b)
#define QNAV_CLI_COMMAND(name, summary, setup)                             \
  static const bool QNAV_COMMAND_CAT(qnav_command_registered_, __LINE__) = \
      ::qnav::cli::register_command({name, summary, setup})
