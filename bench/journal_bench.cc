// Durable appends per second through the journal (server/store/): SQLite in a temporary data
// directory (WAL, synchronous=FULL) and PostgreSQL 15 in a throwaway local cluster
// (tests/support/postgres_cluster.h; fsync and synchronous_commit on, as shipped), from 1, 8 and
// 64 threads. Each thread appends to a world of its own, as a table's seat would, entries of
// about 200 bytes (a shot request). Every Append returns only once its batch is committed, so
// items_per_second is durable appends per second and ops_per_txn shows the group commit.
//
//   build-store/bin/journal_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "benchmark/benchmark.h"
#include "server/store/store.h"
#include "server/store/testing.h"
#include "tests/support/postgres_cluster.h"

namespace sportsim::server::store {
namespace {

enum class Backend { kSqlite, kPostgres };

/// A temporary data directory, removed at exit.
struct TempDir {
  TempDir() {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern =
        absl::StrCat(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp", "/sportsim-bench-XXXXXX");
    if (::mkdtemp(pattern.data()) != nullptr) path = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    if (!path.empty()) std::filesystem::remove_all(path, ec);
  }
  std::string path;
};

/// One store per backend for the whole run (made on first use).
absl::StatusOr<Store*> SharedStore(Backend backend) {
  if (backend == Backend::kSqlite) {
    static TempDir dir;
    static absl::StatusOr<std::unique_ptr<Store>> store =
        Store::Open(StoreOptions{.data_dir = dir.path + "/data"});
    if (!store.ok()) return store.status();
    return store->get();
  }
  static absl::StatusOr<std::unique_ptr<Store>> store =
      []() -> absl::StatusOr<std::unique_ptr<Store>> {
    absl::StatusOr<sportsim::testing::PostgresCluster*> cluster =
        sportsim::testing::PostgresCluster::Shared();
    if (!cluster.ok()) return cluster.status();
    return Store::Open(StoreOptions{.postgres_uri = (*cluster)->uri(), .node = "bench"});
  }();
  if (!store.ok()) return store.status();
  return store->get();
}

/// About 200 bytes that do not compress, as a serialized shot request would be.
std::string Body(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::string body(200, '\0');
  for (char& c : body) c = static_cast<char>(rng());
  return body;
}

std::atomic<uint64_t> next_world{0};

void BM_DurableAppend(benchmark::State& state, Backend backend) {
  absl::StatusOr<Store*> store = SharedStore(backend);
  if (!store.ok()) {
    state.SkipWithError(std::string(store.status().message()).c_str());
    return;
  }
  const uint64_t n = next_world.fetch_add(1);
  const std::string world = absl::StrFormat("t-%012x", n);
  const std::string body = Body(n);
  const StoreStats before = (*store)->stats();
  uint64_t index = 0;
  for (auto _ : state) {
    ++index;
    const absl::Status s = (*store)->Append(JournalEntry{.world_id = world,
                                                         .kind = "table",
                                                         .index = index,
                                                         .tick = static_cast<int64_t>(index),
                                                         .seat = 0,
                                                         .type = index == 1 ? 0u : 1u,
                                                         .body = body,
                                                         .anchor_s = (*store)->NodeSeconds()});
    if (!s.ok()) {
      state.SkipWithError(std::string(s.message()).c_str());
      break;
    }
  }
  state.SetItemsProcessed(state.iterations());
  if (state.thread_index() == 0) {
    // Over the whole run of every thread (approximately: threads end at slightly different
    // times).
    const StoreStats after = (*store)->stats();
    const int64_t txns = after.batches - before.batches;
    state.counters["ops_per_txn"] =
        txns > 0 ? static_cast<double>(after.ops - before.ops) / static_cast<double>(txns) : 0.0;
  }
}

BENCHMARK_CAPTURE(BM_DurableAppend, sqlite, Backend::kSqlite)
    ->Threads(1)
    ->Threads(8)
    ->Threads(64)
    ->UseRealTime()
    ->MinTime(1.0);
BENCHMARK_CAPTURE(BM_DurableAppend, postgres, Backend::kPostgres)
    ->Threads(1)
    ->Threads(8)
    ->Threads(64)
    ->UseRealTime()
    ->MinTime(1.0);

}  // namespace
}  // namespace sportsim::server::store

BENCHMARK_MAIN();
