#include "server/store/testing.h"

#include "server/store/store_internal.h"

namespace sportsim::server::store {
namespace {

StoreInternals& Internals(Store& store) { return dynamic_cast<StoreInternals&>(store); }

}  // namespace

absl::Status ExecForTesting(Store& store, const std::string& sql) {
  return Internals(store).ExecForTesting(sql);
}

void StopClockForTesting(Store& store) { Internals(store).writer().StopClockForTesting(); }

}  // namespace sportsim::server::store
