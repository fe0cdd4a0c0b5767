#include "firmware/cli/cli_app.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace qnav::cli {

void configure(CLI::App& app) {
  app.get_formatter()->column_width(36);
  app.get_formatter()->label("REQUIRED", "(required)");
  app.option_defaults()->always_capture_default(false);
}

std::string format_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

CLI::App& selected(CLI::App& app) {
  CLI::App* a = &app;
  for (;;) {
    const std::vector<CLI::App*> subs = a->get_subcommands();
    if (subs.empty()) return *a;
    a = subs.front();
  }
}

namespace {
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0u : 1u)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string full_name(const CLI::App& a) {
  std::string n = a.get_name();
  for (const CLI::App* p = a.get_parent(); p != nullptr; p = p->get_parent()) n = p->get_name() + " " + n;
  return n;
}

// Every option name (--long and -s) and subcommand name valid at `a` (its parents' options too,
// since CLI11 lets an unknown option fall through to them only when asked; here they do not).
std::vector<std::string> names_at(CLI::App& a) {
  std::vector<std::string> out;
  for (const CLI::Option* o : a.get_options()) {
    for (const std::string& l : o->get_lnames()) out.push_back("--" + l);
    for (const std::string& s : o->get_snames()) out.push_back("-" + s);
  }
  for (const CLI::App* s : a.get_subcommands({})) out.push_back(s->get_name());
  return out;
}
// The help of `a` and of every subcommand below it, each under its full name (the man page's text).
void print_help_tree(const CLI::App& a, const std::string& prev) {
  const std::string name = prev.empty() ? a.get_name() : prev + " " + a.get_name();
  if (!prev.empty()) std::printf("\n==== %s ====\n", name.c_str());
  std::fputs(a.help(prev).c_str(), stdout);
  for (const CLI::App* s : a.get_subcommands([](const CLI::App*) { return true; })) print_help_tree(*s, name);
}
}  // namespace

std::string closest(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::string::npos;
  for (const std::string& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  // A likely typo: two edits or a third of the word, and never half of it.
  return best_d <= std::max<std::size_t>(2, word.size() / 3) && 2 * best_d <= word.size() ? best : std::string();
}

int parse(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
    return -1;
  } catch (const CLI::CallForHelp&) {
    std::fputs(app.help().c_str(), stdout);
    return 0;
  } catch (const CLI::CallForAllHelp&) {
    print_help_tree(app, "");
    return 0;
  } catch (const CLI::ParseError& e) {
    CLI::App& at = selected(app);
    const std::string where = full_name(at);
    const std::vector<std::string> extras = app.remaining(true);
    if (!extras.empty()) {
      const std::string& bad = extras.front();
      const bool is_option = bad.size() > 1 && bad[0] == '-' && !(bad[1] >= '0' && bad[1] <= '9') && bad[1] != '.';
      std::string msg = where + ": " + (is_option ? "unknown option '" : "unexpected argument '") + bad + "'";
      const std::string near = closest(bad, names_at(at));
      if (!near.empty()) msg += " (did you mean '" + near + "'?)";
      std::size_t more = 0;  // other unknown options (the words after an unknown option are its value)
      for (std::size_t k = 1; k < extras.size(); ++k) more += extras[k].size() > 1 && extras[k][0] == '-' ? 1u : 0u;
      if (more > 0) msg += " and " + std::to_string(more) + " more unknown option(s)";
      std::fprintf(stderr, "%s\n", msg.c_str());
    } else {
      std::string msg = e.what();
      const CLI::App& cat = at;
      const std::vector<const CLI::App*> subs = cat.get_subcommands([](const CLI::App*) { return true; });
      if (at.get_subcommands().empty() && !subs.empty() && at.get_require_subcommand_min() > 0) {
        msg = "give a subcommand:";
        for (const CLI::App* s : subs) msg += " " + s->get_name();
      }
      std::fprintf(stderr, "%s: %s\n", where.c_str(), msg.c_str());
    }
    std::fprintf(stderr, "Run '%s --help' for the options.\n", where.c_str());
    return 2;
  }
}

CLI::Option* add_text(CLI::App& app, const std::string& name, std::string& var, const std::string& what,
                      const std::vector<std::string>& choices) {
  std::string d = what;
  if (!choices.empty()) {
    d += " (one of";
    for (const std::string& c : choices) d += " " + c;
    d += ")";
  }
  if (!var.empty()) d += " (default " + var + ")";
  CLI::Option* o = app.add_option(name, var, d);
  if (!choices.empty()) {
    std::string list;
    for (const std::string& c : choices) list += (list.empty() ? "" : ", ") + c;
    o->check(CLI::Validator(
        [choices, list](std::string& s) -> std::string {
          return std::find(choices.begin(), choices.end(), s) != choices.end() ? std::string()
                                                                              : "'" + s + "' is not one of " + list;
        },
        ""));
  }
  return o->type_name("TEXT");
}

CLI::Option* add_positional(CLI::App& app, const std::string& name, std::string& var, const std::string& what) {
  return app.add_option(name, var, what)->required()->type_name("");
}

CLI::Option* add_flag(CLI::App& app, const std::string& name, bool& var, const std::string& what) {
  return app.add_flag(name, var, what);
}

std::string input_file_problem(const std::string& path, bool allow_empty) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int e = errno;
    return path + ": " + std::strerror(e) + (e == ENOENT ? " (check the path)" : e == EACCES ? " (check the file's permissions)" : "");
  }
  if (S_ISDIR(st.st_mode)) return path + ": is a directory (give a file)";
  if (S_ISREG(st.st_mode) && st.st_size == 0 && !allow_empty) return path + ": empty file";
  FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    const int e = errno;
    return path + ": " + std::strerror(e) + (e == EACCES ? " (check the file's permissions)" : "");
  }
  std::fclose(f);
  return std::string();
}

std::string input_dir_problem(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int e = errno;
    return path + ": " + std::strerror(e) + (e == ENOENT ? " (check the path)" : "");
  }
  if (!S_ISDIR(st.st_mode)) return path + ": not a directory (give the folder)";
  if (::access(path.c_str(), R_OK | X_OK) != 0) {
    const int e = errno;
    return path + ": " + std::strerror(e) + " (check the folder's permissions)";
  }
  return std::string();
}

std::string make_dirs(const std::string& dir) {
  if (dir.empty()) return std::string();
  std::string part;
  std::size_t pos = 0;
  while (pos != std::string::npos) {
    pos = dir.find('/', pos + 1);
    part = dir.substr(0, pos);
    if (part.empty()) continue;
    if (::mkdir(part.c_str(), 0777) != 0 && errno != EEXIST) {
      const int e = errno;
      return "cannot create folder " + part + ": " + std::strerror(e);
    }
  }
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) return dir + ": exists and is not a folder";
  return std::string();
}

std::string make_parent_dirs(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  if (slash == std::string::npos || slash == 0) return std::string();
  return make_dirs(path.substr(0, slash));
}

std::FILE* open_output(const char* who, const std::string& path) {
  if (const std::string e = make_parent_dirs(path); !e.empty()) {
    std::fprintf(stderr, "%s: %s\n", who, e.c_str());
    return nullptr;
  }
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) std::fprintf(stderr, "%s: cannot write %s: %s\n", who, path.c_str(), std::strerror(errno));
  return f;
}

}  // namespace qnav::cli
