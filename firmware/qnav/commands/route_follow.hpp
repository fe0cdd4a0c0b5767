// `qnav route follow`: declared on the `route` command by setup_route (route.cpp).
#pragma once

namespace CLI {
class App;
}
namespace qnav::cli {
class Runner;
}

void setup_route_follow(CLI::App& route_cmd, qnav::cli::Runner& run);
