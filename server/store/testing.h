// Hooks into a Store for tests and benchmarks only (tests/server/store_test.cc,
// bench/journal_bench.cc): never used by the server.
#ifndef SPORTSIM_SERVER_STORE_TESTING_H_
#define SPORTSIM_SERVER_STORE_TESTING_H_

#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "server/store/store.h"

namespace sportsim::server::store {

/// Runs `sql` on the store's own connection, between two batches (SQLite:
/// "PRAGMA max_page_count = N" to make the disk look full).
absl::Status ExecForTesting(Store& store, const std::string& sql);
/// The store stops persisting its clock and renewing its lease, as a node that hangs would;
/// writes still go through while the lease lasts.
void StopClockForTesting(Store& store);

}  // namespace sportsim::server::store

#endif  // SPORTSIM_SERVER_STORE_TESTING_H_
