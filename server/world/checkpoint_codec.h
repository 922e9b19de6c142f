// What every kind's journal checkpoint shares (server/billiards/table_checkpoint.h,
// server/swing/session_checkpoint.h): the CRC-32C trailer that seals the bytes, the checks that
// open them (checksum, message, version, no unknown field), errors that name a field by its
// path, and a comparison that reports the first difference with doubles compared by their bits.
// Pure translation: no world, no lock.
//
// A checkpoint message (proto/sportsim/store/v1/*_state.proto) has `uint32 version = 1` and
// `fixed32 crc32c = 15`. Its bytes end with crc32c, written last: 5 bytes, the tag 0x7d and the
// CRC-32C of every byte before it, little-endian. A message cut short at a field boundary still
// parses, and a flipped bit in a double still decodes, so only the checksum tells a damaged or
// truncated checkpoint from a good one.
#ifndef SPORTSIM_SERVER_WORLD_CHECKPOINT_CODEC_H_
#define SPORTSIM_SERVER_WORLD_CHECKPOINT_CODEC_H_

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace google::protobuf {
class Message;
}  // namespace google::protobuf

namespace sportsim::server::checkpoint {

/// CRC-32C (Castagnoli; iSCSI, RFC 3720): "123456789" gives 0xe3069283.
uint32_t Crc32c(std::string_view bytes);

/// `message` serialized, then the trailer (field 15: the CRC-32C of the bytes before it).
/// The message leaves its own crc32c unset.
std::string Seal(const google::protobuf::Message& message);

/// Parses what Seal wrote into `message`. `what` starts every error message ("table
/// checkpoint: "). DATA_LOSS when the bytes are damaged or cut short (the checksum), are not
/// such a message, hold crc32c before the end, or hold a field number the message does not
/// know, at any depth (a newer writer: a new field bumps the version); INVALID_ARGUMENT for a
/// version other than `version`. Never crashes on any input.
absl::Status Open(std::string_view bytes, std::string_view what, uint32_t version,
                  google::protobuf::Message* message);

/// DATA_LOSS "<what><path>: unknown field N" for the first field number `m` (or a message
/// under it) does not know; `path` names `m` ("" : the top). For messages a checkpoint stores
/// serialized inside a bytes field.
absl::Status CheckNoUnknownFields(const google::protobuf::Message& m, std::string_view what,
                                  const std::string& path);

/// DATA_LOSS "<what><path>: <problem>".
absl::Status Corrupt(std::string_view what, std::string_view path, std::string_view problem);

/// Field paths: Member("game", "scores") is "game.scores" (Member("", "x") is "x"),
/// Index("record", 3) is "record[3]".
std::string Member(std::string_view path, std::string_view name);
std::string Index(std::string_view path, size_t i);

/// Values as a difference shows them: a double with its bits, a string quoted and cut at 48
/// bytes with its length, a bool as true/false.
std::string Show(double v);
std::string Show(const std::string& s);
template <typename T>
  requires std::is_integral_v<T>
std::string Show(T v) {
  if constexpr (std::is_same_v<T, bool>) {
    return v ? "true" : "false";
  } else {
    return absl::StrCat(v);
  }
}

/// Walks two values member by member and keeps the first difference as "path: a vs b"; after
/// it, every call is a no-op. Doubles differ when their bits do (-0.0 is not 0.0; NaNs differ
/// by payload).
class Differ {
 public:
  const std::string& first() const { return first_; }
  bool found() const { return !first_.empty(); }

  void Bits(const std::string& path, double a, double b) {
    if (!found() && std::bit_cast<uint64_t>(a) != std::bit_cast<uint64_t>(b)) {
      first_ = absl::StrCat(path, ": ", Show(a), " vs ", Show(b));
    }
  }
  template <typename T>
    requires std::is_integral_v<T>
  void Same(const std::string& path, T a, T b) {
    if (!found() && a != b) first_ = absl::StrCat(path, ": ", Show(a), " vs ", Show(b));
  }
  template <typename E>
    requires std::is_enum_v<E>
  void Same(const std::string& path, E a, E b) {
    Same(path, static_cast<int>(a), static_cast<int>(b));
  }
  void Same(const std::string& path, const std::string& a, const std::string& b) {
    if (!found() && a != b) first_ = absl::StrCat(path, ": ", Show(a), " vs ", Show(b));
  }
  void Same(const std::string& path, const std::vector<std::string>& a,
            const std::vector<std::string>& b) {
    if (Size(path, a.size(), b.size())) {
      for (size_t i = 0; i < a.size(); ++i) Same(Index(path, i), a[i], b[i]);
    }
  }
  template <typename T, size_t N>
  void Same(const std::string& path, const std::array<T, N>& a, const std::array<T, N>& b) {
    for (size_t i = 0; i < N; ++i) Same(Index(path, i), a[i], b[i]);
  }
  /// Two messages of one type by MessageDifferencer (presence, every field at any depth,
  /// unknown fields), doubles and floats by their bits; the difference is its first report
  /// line ("params: modified: gravity_mps2: -0 -> 0").
  void Same(const std::string& path, const google::protobuf::Message& a,
            const google::protobuf::Message& b);
  /// False (and the difference noted) when the sizes differ.
  bool Size(const std::string& path, size_t a, size_t b);
  /// False (and the difference noted) when one has a value and the other not; else whether
  /// both have one (the caller compares the values then).
  template <typename T>
  bool Presence(const std::string& path, const std::optional<T>& a, const std::optional<T>& b) {
    Presence(path, a.has_value(), b.has_value());
    return !found() && a.has_value();
  }
  void Presence(const std::string& path, bool a, bool b) {
    if (!found() && a != b) {
      first_ = absl::StrCat(path, a ? ": present vs absent" : ": absent vs present");
    }
  }

 private:
  std::string first_;
};

}  // namespace sportsim::server::checkpoint

#endif  // SPORTSIM_SERVER_WORLD_CHECKPOINT_CODEC_H_
