#include "server/world/checkpoint_codec.h"

#include <climits>

#include "absl/strings/escaping.h"
#include "absl/strings/str_format.h"
#include "google/protobuf/descriptor.h"
#include "google/protobuf/message.h"
#include "google/protobuf/unknown_field_set.h"
#include "google/protobuf/util/field_comparator.h"
#include "google/protobuf/util/message_differencer.h"

namespace sportsim::server::checkpoint {

namespace {

namespace pb = ::google::protobuf;

// The trailer: field 15 (fixed32, tag 0x7d) holding the CRC-32C of every byte before it.
constexpr char kCrcTag = static_cast<char>((15 << 3) | 5);
constexpr size_t kTrailerBytes = 5;
constexpr int kVersionField = 1;
constexpr int kCrcField = 15;

constexpr std::array<uint32_t, 256> MakeCrcTable() {
  std::array<uint32_t, 256> table{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) != 0 ? (c >> 1) ^ 0x82F63B78u : c >> 1;
    table[i] = c;
  }
  return table;
}
constexpr std::array<uint32_t, 256> kCrcTable = MakeCrcTable();

// The checkpoint message's own field `number`, which every checkpoint message declares with
// this name and type; a message without it is a programming error, caught by the first test.
const pb::FieldDescriptor* OwnField(const pb::Message& m, int number, std::string_view name,
                                    pb::FieldDescriptor::CppType type) {
  const pb::FieldDescriptor* f = m.GetDescriptor()->FindFieldByNumber(number);
  if (f == nullptr || f->name() != name || f->cpp_type() != type || f->is_repeated()) {
    return nullptr;
  }
  return f;
}

}  // namespace

uint32_t Crc32c(std::string_view bytes) {
  uint32_t c = 0xFFFFFFFFu;
  for (char ch : bytes) c = kCrcTable[(c ^ static_cast<uint8_t>(ch)) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

std::string Seal(const pb::Message& message) {
  std::string bytes = message.SerializeAsString();
  const uint32_t crc = Crc32c(bytes);
  bytes.push_back(kCrcTag);
  for (int shift = 0; shift < 32; shift += 8) bytes.push_back(static_cast<char>(crc >> shift));
  return bytes;
}

absl::Status Open(std::string_view bytes, std::string_view what, uint32_t version,
                  pb::Message* message) {
  const pb::FieldDescriptor* version_field =
      OwnField(*message, kVersionField, "version", pb::FieldDescriptor::CPPTYPE_UINT32);
  const pb::FieldDescriptor* crc_field =
      OwnField(*message, kCrcField, "crc32c", pb::FieldDescriptor::CPPTYPE_UINT32);
  if (version_field == nullptr || crc_field == nullptr) {
    return absl::InternalError(absl::StrFormat(
        "%s%s has no `uint32 version = 1` and `fixed32 crc32c = 15`", what,
        message->GetDescriptor()->full_name()));
  }
  if (bytes.size() > static_cast<size_t>(INT_MAX)) {
    return absl::DataLossError(
        absl::StrFormat("%s%d bytes, more than a message can hold", what, bytes.size()));
  }
  if (bytes.size() < kTrailerBytes || bytes[bytes.size() - kTrailerBytes] != kCrcTag) {
    return absl::DataLossError(absl::StrFormat(
        "%s%d bytes that do not end with the crc32c field: not a checkpoint, or cut short",
        what, bytes.size()));
  }
  const std::string_view body = bytes.substr(0, bytes.size() - kTrailerBytes);
  uint32_t stored = 0;
  for (size_t i = 0; i < 4; ++i) {
    stored |= static_cast<uint32_t>(static_cast<uint8_t>(bytes[body.size() + 1 + i])) << (8 * i);
  }
  if (const uint32_t crc = Crc32c(body); crc != stored) {
    return absl::DataLossError(absl::StrFormat(
        "%scrc32c %08x, but the %d bytes before it give %08x: damaged or cut short", what,
        stored, body.size(), crc));
  }
  if (!message->ParseFromArray(body.data(), static_cast<int>(body.size()))) {
    return absl::DataLossError(absl::StrFormat("%sthe %d bytes are not a %s message", what,
                                               bytes.size(),
                                               message->GetDescriptor()->full_name()));
  }
  const pb::Reflection* r = message->GetReflection();
  if (r->GetUInt32(*message, crc_field) != 0) {
    return Corrupt(what, "crc32c", "found before the end");
  }
  if (const uint32_t v = r->GetUInt32(*message, version_field); v != version) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%sversion %d, but this server reads only version %d (%d bytes)", what,
                        v, version, bytes.size()));
  }
  return CheckNoUnknownFields(*message, what, "");
}

absl::Status CheckNoUnknownFields(const pb::Message& m, std::string_view what,
                                  const std::string& path) {
  const pb::Reflection* r = m.GetReflection();
  const pb::UnknownFieldSet& unknown = r->GetUnknownFields(m);
  if (!unknown.empty()) {
    return Corrupt(what, path.empty() ? "(top)" : path,
                   absl::StrFormat("unknown field %d (a newer writer, or damaged bytes)",
                                   unknown.field(0).number()));
  }
  std::vector<const pb::FieldDescriptor*> fields;
  r->ListFields(m, &fields);
  for (const pb::FieldDescriptor* f : fields) {
    if (f->cpp_type() != pb::FieldDescriptor::CPPTYPE_MESSAGE) continue;
    const std::string sub = Member(path, f->name());
    if (f->is_repeated()) {
      for (int i = 0; i < r->FieldSize(m, f); ++i) {
        if (absl::Status s = CheckNoUnknownFields(r->GetRepeatedMessage(m, f, i), what,
                                                  Index(sub, static_cast<size_t>(i)));
            !s.ok()) {
          return s;
        }
      }
    } else if (absl::Status s = CheckNoUnknownFields(r->GetMessage(m, f), what, sub); !s.ok()) {
      return s;
    }
  }
  return absl::OkStatus();
}

absl::Status Corrupt(std::string_view what, std::string_view path, std::string_view problem) {
  return absl::DataLossError(absl::StrFormat("%s%s: %s", what, path, problem));
}

std::string Member(std::string_view path, std::string_view name) {
  return path.empty() ? std::string(name) : absl::StrFormat("%s.%s", path, name);
}

std::string Index(std::string_view path, size_t i) { return absl::StrFormat("%s[%d]", path, i); }

std::string Show(double v) {
  return absl::StrFormat("%.17g (bits %016x)", v, std::bit_cast<uint64_t>(v));
}

std::string Show(const std::string& s) {
  constexpr size_t kMax = 48;
  return absl::StrCat("\"", absl::CEscape(s.substr(0, kMax)), s.size() > kMax ? "\"..." : "\"",
                      absl::StrFormat(" (%d bytes)", s.size()));
}

bool Differ::Size(const std::string& path, size_t a, size_t b) {
  if (!found() && a != b) first_ = absl::StrFormat("%s: %d vs %d elements", path, a, b);
  return !found();
}

namespace {

// Doubles and floats by their bits (-0.0 is not 0.0, NaNs differ by payload); every other
// field as MessageDifferencer compares it.
class BitsComparator final : public pb::util::SimpleFieldComparator {
 public:
  ComparisonResult Compare(const pb::Message& a, const pb::Message& b,
                           const pb::FieldDescriptor* f, int index_a, int index_b,
                           const pb::util::FieldContext* context) override {
    const pb::Reflection* ra = a.GetReflection();
    const pb::Reflection* rb = b.GetReflection();
    const bool rep = f->is_repeated();
    switch (f->cpp_type()) {
      case pb::FieldDescriptor::CPPTYPE_DOUBLE: {
        const double x = rep ? ra->GetRepeatedDouble(a, f, index_a) : ra->GetDouble(a, f);
        const double y = rep ? rb->GetRepeatedDouble(b, f, index_b) : rb->GetDouble(b, f);
        return std::bit_cast<uint64_t>(x) == std::bit_cast<uint64_t>(y) ? SAME : DIFFERENT;
      }
      case pb::FieldDescriptor::CPPTYPE_FLOAT: {
        const float x = rep ? ra->GetRepeatedFloat(a, f, index_a) : ra->GetFloat(a, f);
        const float y = rep ? rb->GetRepeatedFloat(b, f, index_b) : rb->GetFloat(b, f);
        return std::bit_cast<uint32_t>(x) == std::bit_cast<uint32_t>(y) ? SAME : DIFFERENT;
      }
      default:
        return SimpleCompare(a, b, f, index_a, index_b, context);
    }
  }
};

}  // namespace

void Differ::Same(const std::string& path, const pb::Message& a, const pb::Message& b) {
  if (found()) return;
  if (a.GetDescriptor() != b.GetDescriptor()) {
    first_ = absl::StrCat(path, ": ", a.GetDescriptor()->full_name(), " vs ",
                          b.GetDescriptor()->full_name());
    return;
  }
  std::string report;
  bool same = false;
  {
    BitsComparator bits;
    pb::util::MessageDifferencer differ;
    differ.set_field_comparator(&bits);
    differ.ReportDifferencesToString(&report);
    same = differ.Compare(a, b);
  }  // the report is complete once the differencer is gone
  // Its first line: "modified: gravity_mps2: 0 -> -0", "added: gravity_mps2: 0", ...
  if (!same) first_ = absl::StrCat(path, ": ", report.substr(0, report.find('\n')));
}

}  // namespace sportsim::server::checkpoint
