// Quoting a user's input in an error message: a short prefix only (messages travel in gRPC's
// metadata and in logs), printable ASCII only.
#ifndef SPORTSIM_SIM_CORE_QUOTE_H_
#define SPORTSIM_SIM_CORE_QUOTE_H_

#include <cstddef>
#include <string>
#include <string_view>

namespace sportsim {

/// At most the first `max` bytes of `s` between `mark`s, each byte outside printable ASCII
/// as '?', and "..." before the closing mark when `s` was cut: QuoteInput("ab\n") is "ab?"
/// in double quotes.
inline std::string QuoteInput(std::string_view s, size_t max = 24, char mark = '"') {
  std::string out(1, mark);
  for (size_t i = 0; i < s.size() && i < max; ++i) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    out += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '?';
  }
  if (s.size() > max) out += "...";
  out += mark;
  return out;
}

}  // namespace sportsim

#endif  // SPORTSIM_SIM_CORE_QUOTE_H_
