#include "drivers/qnavcan/dbc.hpp"

#include <cstdlib>
#include <cstring>

namespace qnav::drivers::qnavcan {

namespace {
constexpr std::size_t kMaxLine = 1024;

struct Cursor {
  const char* p;
  const char* end;
  void skip_ws() noexcept {
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
  }
  bool eat(char c) noexcept {
    skip_ws();
    if (p < end && *p == c) {
      ++p;
      return true;
    }
    return false;
  }
  bool starts(const char* kw) noexcept {
    skip_ws();
    const std::size_t k = std::strlen(kw);
    if (static_cast<std::size_t>(end - p) >= k && std::memcmp(p, kw, k) == 0 &&
        (static_cast<std::size_t>(end - p) == k || p[k] == ' ' || p[k] == '\t')) {
      p += k;
      return true;
    }
    return false;
  }
  // Identifier [A-Za-z0-9_]+ into out (cap incl. NUL).
  bool ident(char* out, std::size_t cap) noexcept {
    skip_ws();
    std::size_t k = 0;
    while (p < end && ((*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '_')) {
      if (k + 1 >= cap) return false;
      out[k++] = *p++;
    }
    out[k] = '\0';
    return k > 0;
  }
  bool number(double& v) noexcept {
    skip_ws();
    char buf[40];
    std::size_t k = 0;
    while (p < end && k + 1 < sizeof buf &&
           ((*p >= '0' && *p <= '9') || *p == '.' || *p == '-' || *p == '+' || *p == 'e' || *p == 'E')) buf[k++] = *p++;
    buf[k] = '\0';
    if (k == 0) return false;
    char* e = nullptr;
    v = std::strtod(buf, &e);
    return e == buf + k;
  }
  bool uinteger(std::uint64_t& v) noexcept {
    skip_ws();
    std::size_t k = 0;
    v = 0;
    while (p < end && *p >= '0' && *p <= '9' && k < 19) v = v * 10 + static_cast<std::uint64_t>(*p++ - '0'), ++k;
    return k > 0;
  }
  bool quoted(char* out, std::size_t cap) noexcept {
    if (!eat('"')) return false;
    std::size_t k = 0;
    while (p < end && *p != '"') {
      if (k + 1 < cap) out[k++] = *p;
      ++p;
    }
    out[k] = '\0';
    return eat('"');
  }
};

Status parse_signal(Cursor c, DbcSignal& s) noexcept {
  if (!c.ident(s.name, sizeof s.name)) return Status(StatusCode::kCorrupt, "signal name");
  if (!c.eat(':')) {
    char mux[8];
    if (!c.ident(mux, sizeof mux) || !c.eat(':')) return Status(StatusCode::kCorrupt, "expected ':' after signal name");
  }
  std::uint64_t start = 0, len = 0;
  if (!c.uinteger(start) || !c.eat('|') || !c.uinteger(len) || !c.eat('@')) return Status(StatusCode::kCorrupt, "start|length@");
  if (start > 511 || len == 0 || len > 64) return Status(StatusCode::kCorrupt, "start bit or length out of range");
  s.start_bit = static_cast<std::uint16_t>(start);
  s.length = static_cast<std::uint8_t>(len);
  if (c.p >= c.end || (*c.p != '0' && *c.p != '1')) return Status(StatusCode::kCorrupt, "byte order must be 0 or 1");
  s.big_endian = (*c.p++ == '0');
  if (c.p >= c.end || (*c.p != '+' && *c.p != '-')) return Status(StatusCode::kCorrupt, "sign must be + or -");
  s.is_signed = (*c.p++ == '-');
  if (!c.eat('(') || !c.number(s.factor) || !c.eat(',') || !c.number(s.offset) || !c.eat(')'))
    return Status(StatusCode::kCorrupt, "(factor,offset)");
  if (!c.eat('[') || !c.number(s.min) || !c.eat('|') || !c.number(s.max) || !c.eat(']'))
    return Status(StatusCode::kCorrupt, "[min|max]");
  if (!c.quoted(s.unit, sizeof s.unit)) return Status(StatusCode::kCorrupt, "unit string");
  if (s.factor == 0.0) return Status(StatusCode::kCorrupt, "factor 0");
  return Status::ok();
}
}  // namespace

const DbcMessage* DbcFile::find(std::uint32_t id) const noexcept {
  for (const DbcMessage& m : messages)
    if (m.id == id) return &m;
  return nullptr;
}

Status parse_dbc(const char* text, std::size_t n, DbcFile& out) noexcept {
  out.messages.clear();
  out.error_line = 0;
  if (text == nullptr) return Status(StatusCode::kInvalidArgument, "null text");
  std::size_t pos = 0;
  std::size_t line_no = 0;
  DbcMessage* current = nullptr;
  while (pos < n) {
    std::size_t e = pos;
    while (e < n && text[e] != '\n') ++e;
    ++line_no;
    Cursor c{text + pos, text + e};
    pos = e + 1;
    if (c.end - c.p > static_cast<std::ptrdiff_t>(kMaxLine)) {
      out.error_line = line_no;
      return Status(StatusCode::kCorrupt, "DBC line too long");
    }
    auto fail = [&](Status s) {
      out.error_line = line_no;
      return s;
    };
    if (c.starts("BO_")) {
      DbcMessage* m = out.messages.emplace_back();
      if (m == nullptr) return fail(Status(StatusCode::kCapacityExceeded, "too many DBC messages"));
      std::uint64_t id = 0, dlc = 0;
      if (!c.uinteger(id) || !c.ident(m->name, sizeof m->name) || !c.eat(':') || !c.uinteger(dlc) ||
          !c.ident(m->transmitter, sizeof m->transmitter))
        return fail(Status(StatusCode::kCorrupt, "bad BO_ line"));
      if (dlc > 64) return fail(Status(StatusCode::kCorrupt, "DLC > 64"));
      m->extended = (id & 0x80000000u) != 0;
      m->id = static_cast<std::uint32_t>(id & 0x1FFFFFFFu);
      m->dlc = static_cast<std::uint8_t>(dlc);
      current = m;
    } else if (c.starts("SG_")) {
      if (current == nullptr) return fail(Status(StatusCode::kCorrupt, "SG_ before any BO_"));
      DbcSignal* s = current->signals.emplace_back();
      if (s == nullptr) return fail(Status(StatusCode::kCapacityExceeded, "too many signals in a message"));
      const Status st = parse_signal(c, *s);
      if (!st.is_ok()) return fail(st);
    } else if (c.starts("BA_")) {
      char attr[40];
      char kind[8];
      std::uint64_t id = 0, val = 0;
      if (c.quoted(attr, sizeof attr) && std::strcmp(attr, "GenMsgCycleTime") == 0 && c.ident(kind, sizeof kind) &&
          std::strcmp(kind, "BO_") == 0 && c.uinteger(id) && c.uinteger(val)) {
        for (DbcMessage& m : out.messages)
          if (m.id == (id & 0x1FFFFFFFu)) m.cycle_ms = static_cast<std::uint32_t>(val);
      }
      current = nullptr;
    } else {
      c.skip_ws();
      if (c.p < c.end) current = nullptr;  // any other statement ends the signal list
    }
  }
  return Status::ok();
}

}  // namespace qnav::drivers::qnavcan
