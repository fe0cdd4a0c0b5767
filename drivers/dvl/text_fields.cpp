#include "drivers/dvl/text_fields.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>

namespace qnav::drivers::dvl {

bool Field::equals(const char* s) const noexcept {
  const std::size_t k = std::strlen(s);
  return k == n && std::memcmp(p, s, n) == 0;
}

std::size_t split_fields(const char* p, std::size_t n, char sep, Field* out, std::size_t cap) noexcept {
  std::size_t count = 0;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= n; ++i) {
    if (i == n || p[i] == sep) {
      if (count == cap) return cap + 1;
      out[count].p = p + start;
      out[count].n = i - start;
      ++count;
      start = i + 1;
    }
  }
  return count;
}

Field trim(Field f) noexcept {
  while (f.n > 0 && (f.p[0] == ' ' || f.p[0] == '\t')) ++f.p, --f.n;
  while (f.n > 0 && (f.p[f.n - 1] == ' ' || f.p[f.n - 1] == '\t' || f.p[f.n - 1] == '\r')) --f.n;
  return f;
}

namespace {
bool copy(Field f, char* buf) noexcept {
  f = trim(f);
  if (f.n == 0 || f.n > kMaxNumberChars) return false;
  std::memcpy(buf, f.p, f.n);
  buf[f.n] = '\0';
  return true;
}
}  // namespace

bool parse_double(Field f, double& out) noexcept {
  char buf[kMaxNumberChars + 1];
  if (!copy(f, buf)) return false;
  // Only plain decimal numbers: no hex floats, inf or nan spellings.
  for (const char* c = buf; *c; ++c)
    if (!((*c >= '0' && *c <= '9') || *c == '.' || *c == '-' || *c == '+' || *c == 'e' || *c == 'E')) return false;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(buf, &end);
  if (end == buf || *end != '\0' || errno == ERANGE || !std::isfinite(v)) return false;
  out = v;
  return true;
}

bool parse_int(Field f, long long& out) noexcept {
  char buf[kMaxNumberChars + 1];
  if (!copy(f, buf)) return false;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(buf, &end, 10);
  if (end == buf || *end != '\0' || errno == ERANGE) return false;
  out = v;
  return true;
}

}  // namespace qnav::drivers::dvl
