// The qnav tool's command table. Each command lives in its own file under commands/ and registers
// itself at static-initialisation time with QNAV_COMMAND, so adding a command touches no shared file.
// A command receives argv starting at its own name (argv[0] == "xtf" for `qnav xtf info FILE`) and
// returns the process exit code: 0 success, 1 failure of the work, 2 usage error.
#pragma once

namespace qnav::cli {

using CommandFn = int (*)(int argc, char** argv);

struct Command {
  const char* name;     // first word after `qnav`
  const char* summary;  // one line for `qnav help`
  CommandFn run;
};

// Returns false (and the command is not added) when the table is full or the name is taken.
bool register_command(const Command& c) noexcept;
const Command* find_command(const char* name) noexcept;
int command_count() noexcept;
const Command* command_at(int i) noexcept;

}  // namespace qnav::cli

#define QNAV_COMMAND_CAT2(a, b) a##b
#define QNAV_COMMAND_CAT(a, b) QNAV_COMMAND_CAT2(a, b)
#define QNAV_COMMAND(name, summary, fn)                                    \
  static const bool QNAV_COMMAND_CAT(qnav_command_registered_, __LINE__) = \
      ::qnav::cli::register_command({name, summary, fn})
