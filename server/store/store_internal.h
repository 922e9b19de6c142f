// What the two backends share inside server/store/: their factories, the hooks testing.h
// reaches, and the checks of StoreOptions. Not for use outside server/store/.
#ifndef SPORTSIM_SERVER_STORE_STORE_INTERNAL_H_
#define SPORTSIM_SERVER_STORE_STORE_INTERNAL_H_

#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "server/store/group_commit.h"
#include "server/store/store.h"

namespace sportsim::server::store {

/// Opens the SQLite journal in options.data_dir (sqlite_store.cc).
absl::StatusOr<std::unique_ptr<Store>> OpenSqlite(const StoreOptions& options);
/// Opens the PostgreSQL journal at options.postgres_uri as options.node (postgres_store.cc).
absl::StatusOr<std::unique_ptr<Store>> OpenPostgres(const StoreOptions& options);

/// Every store implements this too, for the hooks of testing.h.
class StoreInternals {
 public:
  virtual ~StoreInternals() = default;
  /// The store's writer (its counters, the clock hook).
  virtual GroupCommit& writer() = 0;
  /// Runs `sql` on the writer's connection between batches.
  virtual absl::Status ExecForTesting(const std::string& sql) = 0;
};

/// A store whose writes all go through one GroupCommit writer (both backends): the Journal
/// calls as writer operations. The backend sets `writer_` once open.
class GroupCommitStore : public Store, public StoreInternals {
 public:
  absl::Status Append(JournalEntry entry) override {
    return writer_->Write(JournalOp{.type = JournalOp::Type::kAppend, .entry = std::move(entry)});
  }
  absl::Status Remove(JournalEntry deletion) override {
    return writer_->Write(
        JournalOp{.type = JournalOp::Type::kRemove, .entry = std::move(deletion)});
  }
  void Checkpoint(const std::string& world_id, uint64_t index, int64_t tick,
                  std::string state) override {
    writer_->Post(JournalOp{
        .type = JournalOp::Type::kCheckpoint,
        .entry = {.world_id = world_id, .index = index, .tick = tick, .body = std::move(state)}});
  }
  void Anchor(const std::string& world_id, int64_t tick, double anchor_s) override {
    writer_->Post(JournalOp{.type = JournalOp::Type::kAnchor,
                            .entry = {.world_id = world_id, .tick = tick, .anchor_s = anchor_s}});
  }
  double NodeSeconds() const override { return writer_->NodeSeconds(); }
  absl::Status Healthy() const override { return writer_->Healthy(); }
  GroupCommit& writer() override { return *writer_; }
  StoreStats stats() const override {
    const GroupCommitStats s = writer_->stats();
    return StoreStats{.batches = s.batches,
                      .ops = s.ops,
                      .failed_batches = s.failed_batches,
                      .clock_persists = s.clock_persists};
  }

 protected:
  std::unique_ptr<GroupCommit> writer_;
};

}  // namespace sportsim::server::store

#endif  // SPORTSIM_SERVER_STORE_STORE_INTERNAL_H_
