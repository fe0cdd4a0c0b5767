// qnav: the engineers' tool (train, replay, evaluate, plot, simulate). `qnav help` lists commands.
#include <cstdio>
#include <cstring>

#include "firmware/qnav/command.hpp"

namespace {
void usage() {
  std::printf("usage: qnav COMMAND [ARGS...]\n\ncommands:\n");
  for (int i = 0; i < qnav::cli::command_count(); ++i) {
    const qnav::cli::Command* c = qnav::cli::command_at(i);
    std::printf("  %-10s %s\n", c->name, c->summary);
  }
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::strcmp(argv[1], "help") == 0 || std::strcmp(argv[1], "--help") == 0) {
    usage();
    return argc < 2 ? 2 : 0;
  }
  const qnav::cli::Command* c = qnav::cli::find_command(argv[1]);
  if (c == nullptr) {
    std::fprintf(stderr, "qnav: unknown command '%s' (qnav help lists them)\n", argv[1]);
    return 2;
  }
  return c->run(argc - 1, argv + 1);
}
