#include "test/fuzz/fuzz_support.hpp"
#include "firmware/tools/shared_dir.hpp"

#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#ifndef QNAV_SHARED_DIR
#define QNAV_SHARED_DIR "../shared"
#endif
#ifndef QNAV_SOURCE_DIR
#define QNAV_SOURCE_DIR "."
#endif

namespace qnav::fuzz {

namespace {
std::vector<Target>& registry() {
  static std::vector<Target> r;
  return r;
}

// Never destroyed: the atexit handler below runs after static destructors.
std::vector<std::string>& scratch_files() {
  static auto* f = new std::vector<std::string>();
  return *f;
}

std::vector<std::string>& scratch_dirs() {
  static auto* d = new std::vector<std::string>();
  return *d;
}

void remove_scratch() {
  for (const std::string& f : scratch_files()) ::unlink(f.c_str());
  for (auto it = scratch_dirs().rbegin(); it != scratch_dirs().rend(); ++it) ::rmdir(it->c_str());
  ::rmdir(scratch_dir().c_str());
}
}  // namespace

bool register_target(const Target& t) {
  registry().push_back(t);
  return true;
}

const std::vector<Target>& targets() { return registry(); }

const std::string& scratch_dir() {
  static const std::string& dir = *new std::string([] {
    const char* tmp = std::getenv("TMPDIR");
    std::string d = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/qnav-fuzz-" + std::to_string(::getpid());
    ::mkdir(d.c_str(), 0700);
    std::atexit(remove_scratch);
    return d;
  }());
  return dir;
}

std::string write_scratch(const char* name, const void* data, std::size_t size) {
  const std::string path = scratch_dir() + "/" + name;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) std::abort();  // the harness itself is broken: not a finding about the target
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  std::vector<std::string>& files = scratch_files();
  if (std::find(files.begin(), files.end(), path) == files.end()) files.push_back(path);
  return path;
}

std::string scratch_subdir(const char* rel) {
  const std::string path = scratch_dir() + "/" + rel;
  if (::mkdir(path.c_str(), 0700) == 0) scratch_dirs().push_back(path);
  return path;
}

std::string read_prefix(const std::string& path, std::size_t max_bytes) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return {};
  std::string s(max_bytes, '\0');
  const std::size_t got = std::fread(&s[0], 1, max_bytes, f);
  std::fclose(f);
  s.resize(got);
  return s;
}

void add_file_seed(Seeds& out, const std::string& name, const std::string& path, std::size_t max_bytes) {
  std::string s = read_prefix(path, max_bytes);
  if (!s.empty()) out.push_back(Seed{name, std::move(s)});
}

std::vector<std::string> list_files(const std::string& dir) {
  std::vector<std::string> out;
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return out;
  while (const dirent* e = ::readdir(d)) {
    const std::string path = dir + "/" + e->d_name;
    struct stat st {};
    if (e->d_name[0] != '.' && ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) out.push_back(path);
  }
  ::closedir(d);
  std::sort(out.begin(), out.end());
  return out;
}

std::string shared_dir() { return tools::shared_dir(); }
std::string source_dir() { return QNAV_SOURCE_DIR; }

}  // namespace qnav::fuzz
