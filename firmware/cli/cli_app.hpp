// The command-line conventions of qnav and qnavd, on top of CLI11 (docs/cli.md):
//  - strict: an unknown option, a stray argument, a bad or out-of-range value is an error: exit 2, a
//    message on stderr that names the option (and the closest valid name when one is near);
//  - `--help` (and `-h`) print the help of the (sub)command on stdout, exit 0;
//  - every option's help gives its unit, its default and its allowed range, from the declaration.
// Options are declared with add_number / add_text / add_flag below so they all read alike.
// Also here: input-file checks and output-folder creation that carry the OS reason (strerror).
#pragma once

#include <cmath>
#include <limits>
#include <sstream>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace qnav::cli {

// Applies qnav's help layout to an app and every subcommand made from it afterwards.
void configure(CLI::App& app);

// Parses argv strictly. Returns -1 when the caller should go on, otherwise the exit code to return
// (0 after --help printed on stdout, 2 after a usage error printed on stderr).
int parse(CLI::App& app, int argc, char** argv);

// The candidate nearest to word (edit distance), or "" when none is near enough to be a likely typo.
std::string closest(const std::string& word, const std::vector<std::string>& candidates);

// Deepest subcommand selected by the last parse (the app itself when none).
CLI::App& selected(CLI::App& app);

std::string format_number(double v);

// A numeric option with its unit (may be "" for counts), default (the variable's value now) and
// allowed range [lo, hi]; every value must be finite. Help reads "what (unit; default D; lo..hi)".
template <typename T>
CLI::Option* add_number(CLI::App& app, const std::string& name, T& var, const std::string& what, const std::string& unit,
                        double lo = -std::numeric_limits<double>::infinity(),
                        double hi = std::numeric_limits<double>::infinity()) {
  std::ostringstream d;
  d << what << " (";
  if (!unit.empty()) d << unit << "; ";
  d << "default " << format_number(static_cast<double>(var));
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && has_hi) d << "; " << format_number(lo) << ".." << format_number(hi);
  else if (has_lo) d << "; >= " << format_number(lo);
  else if (has_hi) d << "; <= " << format_number(hi);
  d << ")";
  const std::string range = has_lo && has_hi ? format_number(lo) + ".." + format_number(hi)
                            : has_lo         ? ">= " + format_number(lo)
                            : has_hi         ? "<= " + format_number(hi)
                                             : "a finite number";
  const std::string u = unit;
  CLI::Validator check(
      [lo, hi, range, u](std::string& s) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(s.c_str(), &end);
        if (s.empty() || end == s.c_str() || *end != '\0' || !std::isfinite(v))
          return "'" + s + "' is not a number (allowed: " + range + (u.empty() ? "" : " " + u) + ")";
        if (v < lo || v > hi) return s + " is outside the allowed range " + range + (u.empty() ? "" : " " + u);
        return std::string();
      },
      "");
  return app.add_option(name, var, d.str())->check(check)->type_name(std::numeric_limits<T>::is_integer ? "INT" : "NUM");
}

// A text option (a path, a name, a list); `choices` (when given) are the only allowed values.
CLI::Option* add_text(CLI::App& app, const std::string& name, std::string& var, const std::string& what,
                      const std::vector<std::string>& choices = {});
// A required positional argument.
CLI::Option* add_positional(CLI::App& app, const std::string& name, std::string& var, const std::string& what);
CLI::Option* add_flag(CLI::App& app, const std::string& name, bool& var, const std::string& what);

// "" when path names a readable, non-empty regular file (or a character device such as a pty);
// otherwise the reason, with the fix where there is a common one ("is a directory: give a file").
std::string input_file_problem(const std::string& path, bool allow_empty = false);
// "" when path names a folder that can be listed; otherwise the reason (strerror, "not a directory").
std::string input_dir_problem(const std::string& path);
// Creates a folder and its parents as needed (mkdir -p). "" on success, else the reason with strerror.
std::string make_dirs(const std::string& dir);
// Creates the folder that will hold the file `path` (nothing when path has no folder part).
std::string make_parent_dirs(const std::string& path);
// Opens `path` for writing (text), its folder created first. On failure says why on stderr, prefixed
// by who ("qnav can"), and returns nullptr.
std::FILE* open_output(const char* who, const std::string& path);

}  // namespace qnav::cli
