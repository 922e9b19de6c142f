// What the checkpoint tests (table_checkpoint_test.cc, session_checkpoint_test.cc) share: field
// counts of the types a checkpoint stores, so that a field added to one of them fails their
// build until the checkpoint stores it; and the checks of the shared sealing (checkpoint_codec.h)
// that every kind's checkpoint must pass: the version and trailer written, and every prefix and
// every flipped bit refused.
#ifndef SPORTSIM_TESTS_SERVER_CHECKPOINT_TESTING_H_
#define SPORTSIM_TESTS_SERVER_CHECKPOINT_TESTING_H_

#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/world/checkpoint_codec.h"

namespace sportsim::server {

struct AnyField {
  template <typename T>
  operator T() const;  // NOLINT: converts to any field's type (never called)
};

/// The fields of aggregate T: the most AnyFields it can be brace-initialized from.
template <typename T, typename... A>
constexpr size_t CountFields() {
  if constexpr (requires { T{A{}..., AnyField{}}; }) {
    return CountFields<T, A..., AnyField>();
  } else {
    return sizeof...(A);
  }
}

/// The double with these bits (NaN payloads, -0.0).
inline double Bits(uint64_t bits) { return std::bit_cast<double>(bits); }

/// The message a checkpoint holds (its 5-byte trailer dropped).
template <typename Message>
Message Parsed(const std::string& bytes) {
  Message m;
  EXPECT_TRUE(m.ParseFromString(bytes.substr(0, bytes.size() - 5)));
  return m;
}

/// The checkpoint ends with its trailer (the proto's field 15, fixed32: the CRC-32C of the
/// bytes before it) and says `version`.
template <typename Message>
void ExpectVersionAndTrailer(const std::string& bytes, uint32_t version) {
  ASSERT_GE(bytes.size(), 5u);
  EXPECT_EQ(static_cast<uint8_t>(bytes[bytes.size() - 5]), 0x7D);
  Message m;
  ASSERT_TRUE(m.ParseFromString(bytes));
  EXPECT_EQ(m.version(), version);
  EXPECT_EQ(m.crc32c(), checkpoint::Crc32c(bytes.substr(0, bytes.size() - 5)));
  EXPECT_EQ(checkpoint::Crc32c("123456789"), 0xE3069283u);  // the standard check value
}

/// Every prefix of a real checkpoint, and the checkpoint with any one bit flipped, is refused
/// by `decode` with DATA_LOSS (a prefix's message naming `what`, e.g. "table checkpoint: "),
/// and so is the checkpoint with a byte after it.
template <typename Decode>
void ExpectEveryPrefixAndFlipRefused(const std::string& bytes, Decode decode,
                                     std::string_view what) {
  for (size_t n = 0; n < bytes.size(); ++n) {
    const absl::Status status = decode(bytes.substr(0, n)).status();
    ASSERT_FALSE(status.ok()) << "a prefix of " << n << " of " << bytes.size()
                              << " bytes decoded";
    EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << status;
    EXPECT_THAT(status.message(), ::testing::HasSubstr(what));
  }
  for (size_t i = 0; i < bytes.size(); ++i) {
    for (int bit = 0; bit < 8; ++bit) {
      std::string damaged = bytes;
      damaged[i] = static_cast<char>(damaged[i] ^ (1 << bit));
      const absl::Status status = decode(damaged).status();
      ASSERT_FALSE(status.ok()) << "bit " << bit << " of byte " << i << " flipped, decoded";
      EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << status;
    }
  }
  EXPECT_FALSE(decode(bytes + "x").ok());  // the trailer is no longer last
}

}  // namespace sportsim::server

#endif  // SPORTSIM_TESTS_SERVER_CHECKPOINT_TESTING_H_
