// Shared checks of the libFuzzer targets (tests/fuzz/README.md). A broken invariant prints what
// broke and aborts, so libFuzzer saves the input as a crash; with SPORTSIM_FUZZ_KEEP_GOING=1 set
// it prints the first few and goes on (to survey several findings in one run).
#ifndef SPORTSIM_TESTS_FUZZ_FUZZ_UTIL_H_
#define SPORTSIM_TESTS_FUZZ_FUZZ_UTIL_H_

#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "google/protobuf/descriptor.h"

namespace sportsim::fuzz {

[[gnu::format(printf, 1, 2)]] inline void Fail(const char* fmt, ...) {
  static const bool keep_going = std::getenv("SPORTSIM_FUZZ_KEEP_GOING") != nullptr;
  static int reported = 0;
  if (keep_going && reported >= 20) return;
  std::fprintf(stderr, "INVARIANT BROKEN: ");
  va_list ap;
  va_start(ap, fmt);
  std::vfprintf(stderr, fmt, ap);
  va_end(ap);
  std::fprintf(stderr, "\n");
  ++reported;
  if (!keep_going) std::abort();
}

#define FUZZ_CHECK(cond, ...)                                                       \
  do {                                                                              \
    if (!(cond)) {                                                                  \
      std::fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
      ::sportsim::fuzz::Fail(__VA_ARGS__);                                          \
    }                                                                               \
  } while (0)

/// Every field name (3 characters or more) of a message type and the types it contains.
inline std::set<std::string> FieldNames(const google::protobuf::Descriptor* d) {
  std::set<std::string> names;
  std::set<const google::protobuf::Descriptor*> seen;
  auto walk = [&](auto&& self, const google::protobuf::Descriptor* m) -> void {
    if (!seen.insert(m).second) return;
    for (int i = 0; i < m->field_count(); ++i) {
      const google::protobuf::FieldDescriptor* f = m->field(i);
      if (f->name().size() >= 3) names.insert(f->name());
      if (f->message_type() != nullptr) self(self, f->message_type());
    }
    for (int i = 0; i < m->oneof_decl_count(); ++i) names.insert(m->oneof_decl(i)->name());
  };
  walk(walk, d);
  return names;
}

inline bool IsWordChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

/// Whether `text` holds `word` as a whole word (not inside a longer identifier).
inline bool HasWord(std::string_view text, std::string_view word) {
  for (size_t p = text.find(word); p != std::string_view::npos; p = text.find(word, p + 1)) {
    const bool left = p == 0 || !IsWordChar(text[p - 1]);
    const bool right = p + word.size() == text.size() || !IsWordChar(text[p + word.size()]);
    if (left && right) return true;
  }
  return false;
}

/// Whether the check `tag` is switched off: SPORTSIM_FUZZ_IGNORE holds a comma-separated list of
/// tags ("control", "length", "field", "code") of CheckRequestError and CheckMessage, to look
/// past a finding that is already reported.
inline bool Ignored(std::string_view tag) {
  static const char* const ignore = std::getenv("SPORTSIM_FUZZ_IGNORE");
  if (ignore == nullptr) return false;
  return HasWord(ignore, tag);
}

/// An error a converter returns: not OK, short (< 300 bytes), no raw control characters, and it
/// names one of the request's fields (`fields`: FieldNames of the request).
inline void CheckRequestError(std::string_view what, const absl::Status& s,
                              const std::set<std::string>& fields) {
  FUZZ_CHECK(!s.ok(), "%.*s: error expected", static_cast<int>(what.size()), what.data());
  const std::string m(s.message().data(), s.message().size());
  FUZZ_CHECK(m.size() < 300 || Ignored("length"), "%.*s: error message of %zu bytes: %.300s...",
             static_cast<int>(what.size()), what.data(), m.size(), m.c_str());
  for (char c : m) {
    const auto u = static_cast<unsigned char>(c);
    FUZZ_CHECK((u >= 0x20 && u != 0x7f) || Ignored("control"), "%.*s: raw control character 0x%02x in error: %s",
               static_cast<int>(what.size()), what.data(), u, m.substr(0, 300).c_str());
  }
  bool named = false;
  for (const std::string& f : fields) {
    if (HasWord(m, f)) {
      named = true;
      break;
    }
  }
  FUZZ_CHECK(named || Ignored("field"), "%.*s: error names no request field: %s", static_cast<int>(what.size()),
             what.data(), m.substr(0, 300).c_str());
  FUZZ_CHECK(s.code() == absl::StatusCode::kInvalidArgument ||
                 s.code() == absl::StatusCode::kFailedPrecondition ||
                 s.code() == absl::StatusCode::kOutOfRange ||
                 s.code() == absl::StatusCode::kResourceExhausted || Ignored("code"),
             "%.*s: unexpected status code %s: %s", static_cast<int>(what.size()), what.data(),
             absl::StatusCodeToString(s.code()).c_str(), m.substr(0, 300).c_str());
}

/// Any status the sim returns: short, no raw control characters.
inline void CheckMessage(std::string_view what, const absl::Status& s) {
  const std::string m(s.message().data(), s.message().size());
  FUZZ_CHECK(m.size() < 300 || Ignored("length"), "%.*s: message of %zu bytes", static_cast<int>(what.size()),
             what.data(), m.size());
  for (char c : m) {
    const auto u = static_cast<unsigned char>(c);
    FUZZ_CHECK((u >= 0x20 && u != 0x7f) || Ignored("control"), "%.*s: raw control character 0x%02x in: %s",
               static_cast<int>(what.size()), what.data(), u, m.substr(0, 300).c_str());
  }
}

#define FUZZ_FINITE(x) FUZZ_CHECK(std::isfinite(static_cast<double>(x)), "%s = %g not finite", #x, \
                                  static_cast<double>(x))

/// The bits of a double, for bit-identical comparisons (NaN == NaN, -0 != +0).
inline uint64_t Bits(double x) {
  uint64_t u;
  std::memcpy(&u, &x, sizeof u);
  return u;
}

}  // namespace sportsim::fuzz

#endif  // SPORTSIM_TESTS_FUZZ_FUZZ_UTIL_H_
