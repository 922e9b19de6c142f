#include "server/world/world.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "absl/strings/str_format.h"
#include "openssl/sha.h"
#include "absl/synchronization/mutex.h"

namespace sportsim::server {

uint64_t DeriveSeed(uint64_t seed, uint64_t n) {
  uint64_t z = seed + n * 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

std::string Quote(std::string_view value) {
  constexpr size_t kMax = 24;
  std::string out = "\"";
  for (size_t i = 0; i < value.size() && i < kMax; ++i) {
    const unsigned char c = static_cast<unsigned char>(value[i]);
    out += (c >= 0x20 && c < 0x7f && c != '"' && c != '\\') ? static_cast<char>(c) : '?';
  }
  out += value.size() > kMax ? "\"..." : "\"";
  return out;
}

absl::Status CheckId(std::string_view field, const std::string& id) {
  if (id.empty() || id.size() > 32) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s must be 1 to 32 characters, got %d: %s", field, id.size(), Quote(id)));
  }
  for (const char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_' || c == '-';
    if (!ok) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s may hold only letters, digits, '.', '_' and '-', got %s", field, Quote(id)));
    }
  }
  return absl::OkStatus();
}

absl::Status PrefixStatus(std::string_view prefix, const absl::Status& s) {
  if (s.ok()) return s;
  return absl::Status(s.code(), absl::StrFormat("%s%s", prefix, s.message()));
}

std::string RandomHex(int bytes) {
  static absl::Mutex mu(absl::kConstInit);
  static std::random_device* device = new std::random_device();
  absl::MutexLock lock(&mu);
  std::string out;
  for (int i = 0; i < bytes; i += 4) {
    const uint32_t v = (*device)();
    out += absl::StrFormat("%08x", v);
  }
  return out.substr(0, 2 * static_cast<size_t>(bytes));
}

absl::Status CheckToken(const std::string& token, std::string_view what) {
  // No token, or one no token can be, is a wrong token: PERMISSION_DENIED, like any other
  // (a spectator acting), and checked before anything else is looked up.
  if (token.empty()) {
    return absl::PermissionDeniedError(
        absl::StrFormat("token: none given: acting needs a seat's token (%s returned it)", what));
  }
  if (token.size() > 128) {
    return absl::PermissionDeniedError(absl::StrFormat(
        "token: not a token of this world (%d characters; %s returned the tokens)", token.size(),
        what));
  }
  return absl::OkStatus();
}

absl::StatusOr<std::vector<SeatEntry>> MakeSeats(
    uint32_t count, const google::protobuf::RepeatedPtrField<std::string>& names,
    int default_count, std::vector<std::string>* tokens) {
  if (count > 16 || names.size() > 16) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "seats must be in [1, 16], got %d seats and %d seat_names", count, names.size()));
  }
  const int n = count != 0 ? static_cast<int>(count) : names.size() > 0 ? names.size()
                                                                        : default_count;
  if (names.size() > 0 && names.size() != n) {
    return absl::InvalidArgumentError(
        absl::StrFormat("seat_names: %d names for %d seats", names.size(), n));
  }
  for (int i = 0; i < names.size(); ++i) {
    if (absl::Status s = CheckId(absl::StrFormat("seat_names[%d]", i), names[i]); !s.ok()) {
      return s;
    }
  }
  std::vector<SeatEntry> seats;
  tokens->clear();
  for (int i = 0; i < n; ++i) {
    tokens->push_back(RandomHex(16));
    seats.push_back(SeatEntry{.name = names.size() > 0 ? names[i] : absl::StrFormat("%d", i),
                              .token_hash = HashToken(tokens->back())});
  }
  return seats;
}

void SeatsToProto(const std::vector<SeatEntry>& seats, const std::vector<std::string>* tokens,
                  google::protobuf::RepeatedPtrField<v1::Seat>* out) {
  for (size_t i = 0; i < seats.size(); ++i) {
    v1::Seat* s = out->Add();
    s->set_seat(static_cast<uint32_t>(i));
    s->set_name(seats[i].name);
    if (tokens != nullptr) s->set_token((*tokens)[i]);
  }
}

std::string HashToken(std::string_view token) {
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(reinterpret_cast<const unsigned char*>(token.data()), token.size(), digest);
  return std::string(reinterpret_cast<const char*>(digest), sizeof digest);
}

bool TokensEqual(const std::string& secret_hash, const std::string& given_hash) {
  unsigned diff = secret_hash.size() != given_hash.size() ? 1u : 0u;
  for (size_t j = 0; j < secret_hash.size(); ++j) {
    diff |= static_cast<unsigned char>(secret_hash[j]) ^
            static_cast<unsigned char>(j < given_hash.size() ? given_hash[j] : 0);
  }
  return diff == 0;
}

int SeatOf(const std::vector<SeatEntry>& seats, const std::string& token_hash) {
  int seat = -1;
  for (size_t i = 0; i < seats.size(); ++i) {
    if (TokensEqual(seats[i].token_hash, token_hash)) seat = static_cast<int>(i);
  }
  return seat;
}

SteadyClock::time_point TickClock::Deadline(int64_t k) const {
  return origin + std::chrono::nanoseconds(std::llround(static_cast<double>(k) * 1e9 / tick_hz));
}

int64_t TickClock::DueTick(SteadyClock::time_point now) const {
  const double ns = std::chrono::duration<double, std::nano>(now - origin).count();
  int64_t k = std::max<int64_t>(0, static_cast<int64_t>(std::floor(ns * tick_hz * 1e-9)));
  while (Deadline(k + 1) <= now) ++k;
  while (k > 0 && Deadline(k) > now) --k;
  return k;
}

int64_t TickClock::Tick(SteadyClock::time_point now, int64_t floor) const {
  const double ns = std::chrono::duration<double, std::nano>(now - origin).count();
  return std::max(floor, static_cast<int64_t>(std::floor(ns * tick_hz * 1e-9)));
}

int64_t TickClock::CatchUp(int64_t done, int64_t due, int max_catchup, int64_t* slipped) {
  *slipped = 0;
  if (due - done <= max_catchup) return due;
  *slipped = due - done - max_catchup;
  origin += std::chrono::nanoseconds(std::llround(static_cast<double>(*slipped) * 1e9 / tick_hz));
  return done + max_catchup;
}

}  // namespace sportsim::server
