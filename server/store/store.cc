#include "server/store/store.h"

#include <cmath>

#include "absl/strings/str_format.h"
#include "server/store/store_internal.h"

namespace sportsim::server::store {

absl::StatusOr<std::unique_ptr<Store>> Store::Open(const StoreOptions& options) {
  if (!(options.clock_rate > 0.0) || !std::isfinite(options.clock_rate)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "StoreOptions.clock_rate must be positive and finite, got %g", options.clock_rate));
  }
  if (options.clock_interval <= absl::ZeroDuration() ||
      options.clock_interval == absl::InfiniteDuration()) {
    return absl::InvalidArgumentError(
        absl::StrFormat("StoreOptions.clock_interval must be positive and finite, got %s",
                        absl::FormatDuration(options.clock_interval)));
  }
  if (!options.postgres_uri.empty()) {
    if (options.node.empty() || options.node.size() > 64) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "StoreOptions.node must be 1 to 64 characters, got %d", options.node.size()));
    }
    if (options.lease < absl::Milliseconds(30) || options.lease == absl::InfiniteDuration()) {
      return absl::InvalidArgumentError(
          absl::StrFormat("StoreOptions.lease must be finite and at least 30ms, got %s",
                          absl::FormatDuration(options.lease)));
    }
    return OpenPostgres(options);
  }
  if (options.data_dir.empty()) {
    return absl::InvalidArgumentError(
        "StoreOptions: set data_dir (SQLite) or postgres_uri (PostgreSQL)");
  }
  return OpenSqlite(options);
}

}  // namespace sportsim::server::store
