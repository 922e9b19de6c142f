// The number of fields of an aggregate, at compile time: the checkpoint tests
// (table_checkpoint_test.cc, session_checkpoint_test.cc) pin the field counts of the types a
// checkpoint stores, so that a field added to one of them fails their build until the
// checkpoint stores it.
#ifndef SPORTSIM_TESTS_SERVER_FIELD_COUNT_H_
#define SPORTSIM_TESTS_SERVER_FIELD_COUNT_H_

#include <cstddef>

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

}  // namespace sportsim::server

#endif  // SPORTSIM_TESTS_SERVER_FIELD_COUNT_H_
