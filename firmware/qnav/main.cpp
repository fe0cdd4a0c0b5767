// qnav: the engineers' tool (train, replay, evaluate, plot, simulate). `qnav --help` lists commands,
// `qnav help COMMAND [SUB]` (or `qnav COMMAND [SUB] --help`) prints one command's options.
// Command-line conventions (strict parsing, exit codes): docs/cli.md.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "firmware/cli/cli_app.hpp"
#include "firmware/qnav/command.hpp"
#include "nav/core/assert.hpp"

namespace {
using qnav::cli::Command;
bool g_software_faults = false;

int run(int argc, char** argv) {
  CLI::App app("qnav: the engineers' tool for the qnav navigation daemon (train, replay, evaluate, plot, simulate).\n"
               "Options are strict: an unknown option or a bad value is an error (exit 2). Exit 1: the work failed\n"
               "or processed nothing valid. `qnav help COMMAND` prints a command's options.",
               "qnav");
  qnav::cli::configure(app);
  app.set_help_all_flag("--help-all", "print the help of every command and subcommand");
  app.require_subcommand(1);
  qnav::cli::Runner runner;
  for (int i = 0; i < qnav::cli::command_count(); ++i) {
    const Command* c = qnav::cli::command_at(i);
    c->setup(*app.add_subcommand(c->name, c->summary), runner);
  }
  const int rc = qnav::cli::parse(app, argc, argv);
  if (rc >= 0) return rc;
  CLI::App& leaf = qnav::cli::selected(app);
  const std::function<int()>* action = runner.find(&leaf);
  if (action == nullptr) {  // a command whose subcommand is optional was given none
    std::fputs(leaf.help().c_str(), stderr);
    return 2;
  }
  return (*action)();
}
}  // namespace

// A broken invariant (QNAV_ASSERT, nav/core/assert.hpp) in the tool: named on stderr, and the exit code
// says so (3), whatever the command printed.
static void on_software_fault(const char* what, const char* file, int line) noexcept {
  std::fprintf(stderr, "qnav: software fault (a bug, please report it): %s (%s:%d)\n", what, file, line);
  g_software_faults = true;
}

int main(int argc, char** argv) {
  qnav::set_assert_handler(&on_software_fault);
  if (argc < 2) {
    std::vector<char*> args{argv[0], const_cast<char*>("--help")};
    run(2, args.data());
    std::fprintf(stderr, "qnav: give a command (listed above)\n");
    return 2;
  }
  // `qnav help [COMMAND [SUB...]]` is `qnav [COMMAND [SUB...]] --help`.
  if (std::strcmp(argv[1], "help") == 0) {
    std::vector<char*> args{argv[0]};
    for (int i = 2; i < argc; ++i) args.push_back(argv[i]);
    if (argc >= 3 && qnav::cli::find_command(argv[2]) == nullptr) {
      std::vector<std::string> names;
      for (int i = 0; i < qnav::cli::command_count(); ++i) names.push_back(qnav::cli::command_at(i)->name);
      const std::string near = qnav::cli::closest(argv[2], names);
      std::fprintf(stderr, "qnav help: unknown command '%s'%s (qnav --help lists them)\n", argv[2],
                   near.empty() ? "" : (" (did you mean '" + near + "'?)").c_str());
      return 2;
    }
    static char help[] = "--help";
    args.push_back(help);
    return run(static_cast<int>(args.size()), args.data());
  }
  if (argv[1][0] != '-' && qnav::cli::find_command(argv[1]) == nullptr) {
    std::vector<std::string> names;
    for (int i = 0; i < qnav::cli::command_count(); ++i) names.push_back(qnav::cli::command_at(i)->name);
    const std::string near = qnav::cli::closest(argv[1], names);
    std::fprintf(stderr, "qnav: unknown command '%s'%s (qnav --help lists them)\n", argv[1],
                 near.empty() ? "" : (" (did you mean '" + near + "'?)").c_str());
    return 2;
  }
  const int rc = run(argc, argv);
  return g_software_faults && rc == 0 ? 3 : rc;
}
