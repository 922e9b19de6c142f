// The durable journals (server/store/store.h) against both backends: SQLite in a temporary
// data directory and PostgreSQL 15 in a throwaway cluster (tests/support/postgres_cluster.h,
// one per test program, a fresh database per test).
#include "server/store/store.h"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/store/testing.h"
#include "tests/support/postgres_cluster.h"

namespace sportsim::server::store {
namespace {

using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::SizeIs;
using sportsim::testing::PostgresCluster;

/// An entry whose body holds zero bytes and every byte value.
JournalEntry Entry(const std::string& world, uint64_t index, int64_t tick = 0,
                   double anchor_s = 0.0) {
  std::string body = absl::StrFormat("%s#%d", world, index);
  body.push_back('\0');
  for (int b = 0; b < 256; b += 37) body.push_back(static_cast<char>(b));
  body.push_back('\0');
  return JournalEntry{.world_id = world,
                      .kind = world[0] == 't' ? "table" : "session",
                      .index = index,
                      .tick = tick,
                      .seat = static_cast<int32_t>(index % 3) - 1,
                      .type = static_cast<uint32_t>(index == 1 ? 0 : 100 + index),
                      .body = body,
                      .anchor_s = anchor_s};
}

void ExpectSameEntry(const JournalEntry& got, const JournalEntry& want) {
  EXPECT_EQ(got.world_id, want.world_id);
  EXPECT_EQ(got.kind, want.kind);
  EXPECT_EQ(got.index, want.index);
  EXPECT_EQ(got.tick, want.tick);
  EXPECT_EQ(got.seat, want.seat);
  EXPECT_EQ(got.type, want.type);
  EXPECT_EQ(got.body, want.body);
  EXPECT_EQ(got.anchor_s, want.anchor_s);
}

std::string TempDir() {
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern =
      absl::StrCat(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp", "/sportsim-store-XXXXXX");
  if (::mkdtemp(pattern.data()) == nullptr) return "";
  return pattern;
}

class StoreTest : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    if (sqlite()) {
      dir_ = TempDir();
      ASSERT_FALSE(dir_.empty());
      options_.data_dir = dir_ + "/data";
    } else {
      absl::StatusOr<PostgresCluster*> cluster = PostgresCluster::Shared();
      ASSERT_TRUE(cluster.ok()) << cluster.status();
      cluster_ = *cluster;
      absl::StatusOr<std::string> uri = cluster_->NewDatabase();
      ASSERT_TRUE(uri.ok()) << uri.status();
      options_.postgres_uri = *uri;
      options_.node = "a";
    }
  }
  void TearDown() override {
    if (!dir_.empty()) {
      std::error_code ec;
      std::filesystem::remove_all(dir_, ec);
    }
  }

  bool sqlite() const { return GetParam() == "sqlite"; }

  std::unique_ptr<Store> Open(const StoreOptions& options) {
    absl::StatusOr<std::unique_ptr<Store>> store = Store::Open(options);
    EXPECT_TRUE(store.ok()) << store.status();
    return store.ok() ? *std::move(store) : nullptr;
  }
  std::unique_ptr<Store> Open() { return Open(options_); }

  std::vector<StoredWorld> Load(Store& store) {
    absl::StatusOr<std::vector<StoredWorld>> worlds = store.Load();
    EXPECT_TRUE(worlds.ok()) << worlds.status();
    return worlds.ok() ? *std::move(worlds) : std::vector<StoredWorld>();
  }

  StoreOptions options_;
  std::string dir_;
  PostgresCluster* cluster_ = nullptr;
};

TEST_P(StoreTest, AppendsComeBackInOrderWithTheirBodies) {
  std::unique_ptr<Store> store = Open();
  ASSERT_NE(store, nullptr);
  EXPECT_TRUE(store->Healthy().ok());
  EXPECT_THAT(Load(*store), IsEmpty());
  // 20 worlds, entries interleaved across worlds, bodies with zero bytes.
  std::vector<std::string> ids;
  for (int w = 0; w < 20; ++w) ids.push_back(absl::StrFormat("%s-%02d", w % 2 ? "s" : "t", w));
  for (uint64_t i = 1; i <= 5; ++i) {
    for (const std::string& id : ids) {
      ASSERT_TRUE(store->Append(Entry(id, i, 10 * i, 0.5 * i)).ok());
    }
  }
  std::vector<StoredWorld> worlds = Load(*store);
  ASSERT_THAT(worlds, SizeIs(20));
  for (size_t w = 0; w + 1 < worlds.size(); ++w) {
    EXPECT_LT(worlds[w].world_id, worlds[w + 1].world_id);
  }
  for (const StoredWorld& w : worlds) {
    EXPECT_EQ(w.kind, w.world_id[0] == 't' ? "table" : "session");
    EXPECT_EQ(w.checkpoint_index, 0u);
    EXPECT_EQ(w.checkpoint, "");
    EXPECT_EQ(w.anchor_tick, 50);  // the last entry's
    EXPECT_EQ(w.anchor_s, 2.5);
    EXPECT_EQ(w.clock_s, 0.0);  // a new node's clock as persisted before this Open
    ASSERT_THAT(w.entries, SizeIs(5));
    for (uint64_t i = 1; i <= 5; ++i) {
      ExpectSameEntry(w.entries[i - 1], Entry(w.world_id, i, 10 * i, 0.5 * i));
    }
  }
  EXPECT_THAT(store->Describe(), HasSubstr(sqlite() ? "sqlite:" : "postgresql:127.0.0.1:"));
  if (sqlite()) {
    EXPECT_EQ(store->Describe(), "sqlite:" + options_.data_dir + "/journal.db");
  } else {
    EXPECT_THAT(store->Describe(), HasSubstr(" node a"));
  }
}

TEST_P(StoreTest, EntriesOutOfTurnAreRefusedAndChangeNothing) {
  std::unique_ptr<Store> store = Open();
  ASSERT_NE(store, nullptr);
  ASSERT_TRUE(store->Append(Entry("t-1", 1)).ok());
  const absl::Status gap = store->Append(Entry("t-1", 3));
  EXPECT_EQ(gap.code(), absl::StatusCode::kInternal) << gap;
  EXPECT_THAT(gap.message(), HasSubstr("last entry of that world is 1"));
  const absl::Status again = store->Append(Entry("t-1", 1));
  EXPECT_EQ(again.code(), absl::StatusCode::kAlreadyExists) << again;
  const absl::Status unknown = store->Append(Entry("t-2", 2));
  EXPECT_EQ(unknown.code(), absl::StatusCode::kInternal) << unknown;
  EXPECT_THAT(unknown.message(), HasSubstr("not in the journal"));
  ASSERT_TRUE(store->Append(Entry("t-1", 2)).ok());
  std::vector<StoredWorld> worlds = Load(*store);
  ASSERT_THAT(worlds, SizeIs(1));
  ASSERT_THAT(worlds[0].entries, SizeIs(2));
  EXPECT_EQ(worlds[0].entries[1].index, 2u);
  EXPECT_TRUE(store->Healthy().ok());  // refusals are the entries', not the store's
}

TEST_P(StoreTest, CheckpointCompactsTheEntriesItCoversButKeepsTheCreation) {
  std::unique_ptr<Store> store = Open();
  ASSERT_NE(store, nullptr);
  for (uint64_t i = 1; i <= 10; ++i) ASSERT_TRUE(store->Append(Entry("t-c", i, i)).ok());
  const std::string state("state\0of t-c", 12);
  store->Checkpoint("t-c", 6, 66, state);
  store->Checkpoint("t-c", 3, 33, "older");      // behind the checkpoint: ignored
  store->Checkpoint("t-c", 99, 99, "too far");   // beyond the last entry: ignored
  store->Checkpoint("t-none", 2, 2, "nobody");   // no such world: ignored
  // A write queued after them commits them no later than itself.
  ASSERT_TRUE(store->Append(Entry("t-c", 11, 11)).ok());
  std::vector<StoredWorld> worlds = Load(*store);
  ASSERT_THAT(worlds, SizeIs(1));
  const StoredWorld& w = worlds[0];
  EXPECT_EQ(w.checkpoint_index, 6u);
  EXPECT_EQ(w.checkpoint_tick, 66);
  EXPECT_EQ(w.checkpoint, state);
  std::vector<uint64_t> indexes;
  for (const JournalEntry& e : w.entries) indexes.push_back(e.index);
  EXPECT_EQ(indexes, (std::vector<uint64_t>{1, 7, 8, 9, 10, 11}));
  ExpectSameEntry(w.entries[0], Entry("t-c", 1, 1));
}

TEST_P(StoreTest, RemoveTakesTheWorldItsEntriesAndCheckpoint) {
  std::unique_ptr<Store> store = Open();
  ASSERT_NE(store, nullptr);
  for (uint64_t i = 1; i <= 4; ++i) {
    ASSERT_TRUE(store->Append(Entry("t-gone", i)).ok());
    ASSERT_TRUE(store->Append(Entry("t-kept", i)).ok());
  }
  store->Checkpoint("t-gone", 3, 3, "cp");
  ASSERT_TRUE(store->Remove(Entry("t-gone", 5)).ok());
  store->Checkpoint("t-gone", 4, 4, "late");  // a late checkpoint does not bring it back
  store->Anchor("t-gone", 7, 7.0);
  store->Anchor("t-kept", 1234, 56.5);
  ASSERT_TRUE(store->Append(Entry("t-kept", 5, 9, 3.0)).ok());
  store->Anchor("t-kept", 1234, 56.5);
  ASSERT_TRUE(store->Remove(Entry("t-never", 1)).ok());  // not there: nothing to do
  std::vector<StoredWorld> worlds = Load(*store);
  ASSERT_THAT(worlds, SizeIs(1));
  EXPECT_EQ(worlds[0].world_id, "t-kept");
  EXPECT_THAT(worlds[0].entries, SizeIs(5));
  EXPECT_EQ(worlds[0].anchor_tick, 1234);
  EXPECT_EQ(worlds[0].anchor_s, 56.5);
  // A removed world can be created again under its id.
  ASSERT_TRUE(store->Append(Entry("t-gone", 1)).ok());
  worlds = Load(*store);
  ASSERT_THAT(worlds, SizeIs(2));
  EXPECT_EQ(worlds[0].world_id, "t-gone");
  EXPECT_THAT(worlds[0].entries, SizeIs(1));
  EXPECT_EQ(worlds[0].checkpoint_index, 0u);
}

TEST_P(StoreTest, ConcurrentAppendsAreAllDurableAndShareTransactions) {
  std::unique_ptr<Store> store = Open();
  ASSERT_NE(store, nullptr);
  constexpr int kThreads = 64;
  constexpr int kPerThread = 20;
  std::atomic<int> failed{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      const std::string id = absl::StrFormat("t-%03d", t);
      for (uint64_t i = 1; i <= kPerThread; ++i) {
        if (!store->Append(Entry(id, i, i)).ok()) failed.fetch_add(1);
      }
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(failed.load(), 0);
  const StoreStats stats = store->stats();
  EXPECT_EQ(stats.ops, kThreads * kPerThread);
  EXPECT_LT(stats.batches, kThreads * kPerThread) << "appends were not committed together";
  std::cout << GetParam() << ": " << kThreads * kPerThread << " appends in " << stats.batches
            << " transactions\n";
  std::vector<StoredWorld> worlds = Load(*store);
  ASSERT_THAT(worlds, SizeIs(kThreads));
  for (const StoredWorld& w : worlds) {
    ASSERT_THAT(w.entries, SizeIs(kPerThread));
    for (int i = 0; i < kPerThread; ++i) EXPECT_EQ(w.entries[i].index, uint64_t(i + 1));
  }
}

TEST_P(StoreTest, ReopenKeepsEverythingAndTheClockGoesOn) {
  options_.clock_rate = 2.0;
  options_.clock_interval = absl::Milliseconds(50);
  double reached = 0.0;
  {
    std::unique_ptr<Store> store = Open();
    ASSERT_NE(store, nullptr);
    EXPECT_LT(store->NodeSeconds(), 0.1);
    for (uint64_t i = 1; i <= 3; ++i) {
      ASSERT_TRUE(store->Append(Entry("t-r", i, i, store->NodeSeconds())).ok());
    }
    store->Checkpoint("t-r", 2, 2, "cp");
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    reached = store->NodeSeconds();
    EXPECT_GE(reached, 0.6);  // 0.3 s at clock rate 2
    store->Close();
    store->Close();  // idempotent
    EXPECT_EQ(store->Append(Entry("t-r", 4)).code(), absl::StatusCode::kUnavailable);
  }
  std::unique_ptr<Store> store = Open();
  ASSERT_NE(store, nullptr);
  // Close persisted the clock the node reached: the next run starts there.
  const double start = store->NodeSeconds();
  EXPECT_GE(start, reached);
  EXPECT_LT(start, reached + 1.0);
  std::vector<StoredWorld> worlds = Load(*store);
  ASSERT_THAT(worlds, SizeIs(1));
  EXPECT_GE(worlds[0].clock_s, reached);
  EXPECT_LE(worlds[0].clock_s, start);
  EXPECT_EQ(worlds[0].checkpoint_index, 2u);
  ASSERT_THAT(worlds[0].entries, SizeIs(2));  // the creation and 3
  EXPECT_EQ(worlds[0].entries[1].index, 3u);
  ASSERT_TRUE(store->Append(Entry("t-r", 4)).ok());
}

TEST_P(StoreTest, AfterACrashTheClockResumesFromThePersistedPromise) {
  options_.clock_interval = absl::Milliseconds(200);
  double stopped = 0.0;
  {
    std::unique_ptr<Store> store = Open();
    ASSERT_NE(store, nullptr);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    // As a crash: no more persists, not even the last one at Close.
    StopClockForTesting(*store);
    stopped = store->NodeSeconds();
    store->Close();
  }
  std::unique_ptr<Store> store = Open();
  ASSERT_NE(store, nullptr);
  // The last promise was made at most one interval before the stop (loaded machines aside),
  // for two intervals after it was made.
  const double start = store->NodeSeconds();
  EXPECT_GT(start, stopped);
  EXPECT_LE(start, stopped + 0.4 + 0.05);
}

TEST_P(StoreTest, OptionsAreChecked) {
  StoreOptions bad = options_;
  bad.clock_rate = 0;
  EXPECT_EQ(Store::Open(bad).status().code(), absl::StatusCode::kInvalidArgument);
  bad = options_;
  bad.clock_interval = absl::ZeroDuration();
  EXPECT_EQ(Store::Open(bad).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(Store::Open(StoreOptions{}).status().code(), absl::StatusCode::kInvalidArgument);
}

INSTANTIATE_TEST_SUITE_P(Backends, StoreTest, ::testing::Values("sqlite", "postgres"),
                         [](const ::testing::TestParamInfo<std::string>& backend) {
                           return backend.param;
                         });

// --- SQLite only ---------------------------------------------------------------------------

class SqliteStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = TempDir();
    ASSERT_FALSE(dir_.empty());
    options_.data_dir = dir_ + "/data";
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  StoreOptions options_;
  std::string dir_;
};

TEST_F(SqliteStoreTest, ASecondServerOnTheSameDirectoryIsRefused) {
  absl::StatusOr<std::unique_ptr<Store>> first = Store::Open(options_);
  ASSERT_TRUE(first.ok()) << first.status();
  const absl::StatusOr<std::unique_ptr<Store>> second = Store::Open(options_);
  ASSERT_FALSE(second.ok());
  EXPECT_EQ(second.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(second.status().message(),
            absl::StrFormat("data_dir %s is in use by another sportsim-server (pid %d)",
                            options_.data_dir, ::getpid()));
  (*first)->Close();  // releases the directory
  EXPECT_TRUE(Store::Open(options_).ok());
}

TEST_F(SqliteStoreTest, AnUnusableDirectoryIsRefusedNamingThePathAndReason) {
  // Tests run as root, which ignores permissions: make the paths unusable by their shape.
  const std::string file = dir_ + "/file";
  std::ofstream(file) << "x";
  options_.data_dir = file + "/data";
  absl::Status s = Store::Open(options_).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kFailedPrecondition) << s;
  EXPECT_THAT(s.message(), HasSubstr(file + "/data"));
  EXPECT_THAT(s.message(), HasSubstr("Not a directory"));

  options_.data_dir = dir_ + "/db-is-a-dir";
  std::filesystem::create_directories(options_.data_dir + "/journal.db");
  s = Store::Open(options_).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kFailedPrecondition) << s;
  EXPECT_THAT(s.message(), HasSubstr(options_.data_dir + "/journal.db"));
  EXPECT_THAT(s.message(), HasSubstr("unable to open database file"));

  options_.data_dir = dir_ + "/not-a-db";
  std::filesystem::create_directories(options_.data_dir);
  std::ofstream(options_.data_dir + "/journal.db") << std::string(8192, 'x');
  s = Store::Open(options_).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kFailedPrecondition) << s;
  EXPECT_THAT(s.message(), HasSubstr("not a database"));
}

TEST_F(SqliteStoreTest, AFailedCommitStoresNothingAndIsUnhealthyUntilOneSucceeds) {
  options_.clock_interval = absl::Hours(1);  // no clock persist to mend health meanwhile
  absl::StatusOr<std::unique_ptr<Store>> opened = Store::Open(options_);
  ASSERT_TRUE(opened.ok()) << opened.status();
  Store& store = **opened;
  ASSERT_TRUE(store.Append(Entry("t-full", 1)).ok());
  // The disk is full: the database may not grow by a page.
  ASSERT_TRUE(ExecForTesting(store, "PRAGMA max_page_count = 1").ok());
  JournalEntry big = Entry("t-full", 2);
  big.body.append(256 * 1024, 'b');
  const absl::Status full = store.Append(big);
  EXPECT_EQ(full.code(), absl::StatusCode::kUnavailable) << full;
  EXPECT_THAT(full.message(), HasSubstr("SQLITE_FULL"));
  EXPECT_THAT(full.message(), HasSubstr(options_.data_dir + "/journal.db"));
  EXPECT_EQ(store.Healthy().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(store.Healthy().message(), HasSubstr("SQLITE_FULL"));
  EXPECT_EQ(store.stats().failed_batches, 1);
  absl::StatusOr<std::vector<StoredWorld>> worlds = store.Load();
  ASSERT_TRUE(worlds.ok()) << worlds.status();
  ASSERT_THAT(*worlds, SizeIs(1));
  EXPECT_THAT((*worlds)[0].entries, SizeIs(1));
  EXPECT_EQ((*worlds)[0].anchor_tick, 0);
  // Room again: the same entry goes through and the store is healthy.
  ASSERT_TRUE(ExecForTesting(store, "PRAGMA max_page_count = 1073741823").ok());
  ASSERT_TRUE(store.Append(big).ok());
  EXPECT_TRUE(store.Healthy().ok());
  worlds = store.Load();
  ASSERT_TRUE(worlds.ok());
  EXPECT_THAT((*worlds)[0].entries, SizeIs(2));
}

TEST_F(SqliteStoreTest, AdoptFindsNothing) {
  absl::StatusOr<std::unique_ptr<Store>> store = Store::Open(options_);
  ASSERT_TRUE(store.ok()) << store.status();
  ASSERT_TRUE((*store)->Append(Entry("t-1", 1)).ok());
  absl::StatusOr<std::vector<StoredWorld>> adopted = (*store)->Adopt();
  ASSERT_TRUE(adopted.ok());
  EXPECT_THAT(*adopted, IsEmpty());
}

// --- PostgreSQL only -----------------------------------------------------------------------

class PostgresStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    absl::StatusOr<PostgresCluster*> cluster = PostgresCluster::Shared();
    ASSERT_TRUE(cluster.ok()) << cluster.status();
    cluster_ = *cluster;
    absl::StatusOr<std::string> uri = cluster_->NewDatabase();
    ASSERT_TRUE(uri.ok()) << uri.status();
    uri_ = *uri;
  }
  StoreOptions Node(const std::string& name, absl::Duration lease = absl::Seconds(10)) {
    return StoreOptions{.postgres_uri = uri_,
                        .node = name,
                        .lease = lease,
                        .clock_interval = absl::Milliseconds(50)};
  }
  std::unique_ptr<Store> Open(const StoreOptions& options) {
    absl::StatusOr<std::unique_ptr<Store>> store = Store::Open(options);
    EXPECT_TRUE(store.ok()) << store.status();
    return store.ok() ? *std::move(store) : nullptr;
  }
  PostgresCluster* cluster_ = nullptr;
  std::string uri_;
};

TEST_F(PostgresStoreTest, ASecondProcessOfTheSameNodeFencesTheFirst) {
  std::unique_ptr<Store> first = Open(Node("a"));
  ASSERT_NE(first, nullptr);
  ASSERT_TRUE(first->Append(Entry("t-1", 1)).ok());
  std::unique_ptr<Store> second = Open(Node("a"));
  ASSERT_NE(second, nullptr);
  const absl::Status lost = first->Append(Entry("t-1", 2));
  EXPECT_EQ(lost.code(), absl::StatusCode::kUnavailable) << lost;
  EXPECT_THAT(lost.message(), HasSubstr("lost its lease (epoch 1)"));
  EXPECT_THAT(lost.message(), HasSubstr("epoch 2"));
  EXPECT_EQ(first->Healthy().code(), absl::StatusCode::kUnavailable);
  // For good: nothing the first one does goes through any more.
  EXPECT_EQ(first->Append(Entry("t-2", 1)).code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(first->Load().status().code(), absl::StatusCode::kUnavailable);
  absl::StatusOr<std::vector<StoredWorld>> worlds = second->Load();
  ASSERT_TRUE(worlds.ok()) << worlds.status();
  ASSERT_THAT(*worlds, SizeIs(1));
  EXPECT_THAT((*worlds)[0].entries, SizeIs(1));
  EXPECT_TRUE(second->Append(Entry("t-1", 2)).ok());
  EXPECT_TRUE(second->Healthy().ok());
}

TEST_F(PostgresStoreTest, ANodeAdoptsTheWorldsOfANodeWhoseLeaseLapsed) {
  std::unique_ptr<Store> a = Open(Node("a", absl::Seconds(2)));
  ASSERT_NE(a, nullptr);
  for (uint64_t i = 1; i <= 3; ++i) {
    ASSERT_TRUE(a->Append(Entry("t-a1", i, i, a->NodeSeconds())).ok());
    ASSERT_TRUE(a->Append(Entry("s-a2", i, i, a->NodeSeconds())).ok());
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  // Node a hangs: no more renewals or clock persists.
  StopClockForTesting(*a);
  const double a_clock = a->NodeSeconds();
  std::unique_ptr<Store> b = Open(Node("b"));
  ASSERT_NE(b, nullptr);
  ASSERT_TRUE(b->Append(Entry("t-b1", 1)).ok());
  absl::StatusOr<std::vector<StoredWorld>> adopted = b->Adopt();
  ASSERT_TRUE(adopted.ok()) << adopted.status();
  EXPECT_THAT(*adopted, IsEmpty()) << "a's lease is still valid";

  std::this_thread::sleep_for(std::chrono::milliseconds(2200));
  adopted = b->Adopt();
  ASSERT_TRUE(adopted.ok()) << adopted.status();
  ASSERT_THAT(*adopted, SizeIs(2));
  EXPECT_EQ((*adopted)[0].world_id, "s-a2");
  EXPECT_EQ((*adopted)[1].world_id, "t-a1");
  for (const StoredWorld& w : *adopted) {
    ASSERT_THAT(w.entries, SizeIs(3));
    ExpectSameEntry(w.entries[2], Entry(w.world_id, 3, 3, w.entries[2].anchor_s));
    EXPECT_EQ(w.anchor_tick, 3);
    // a's clock as a last persisted it: a promise past where it had got to.
    EXPECT_GT(w.clock_s, a_clock - 0.06);
    EXPECT_LE(w.clock_s, a_clock + 0.1 + 0.01);
  }
  // Fenced: a can write nothing more, and knows it.
  const absl::Status lost = a->Append(Entry("t-a1", 4));
  EXPECT_EQ(lost.code(), absl::StatusCode::kUnavailable) << lost;
  EXPECT_THAT(lost.message(), HasSubstr("lost its lease"));
  EXPECT_EQ(a->Healthy().code(), absl::StatusCode::kUnavailable);
  // The worlds are b's now: it goes on with them, and they are in its Load.
  EXPECT_TRUE(b->Append(Entry("t-a1", 4)).ok());
  b->Anchor("s-a2", 10, b->NodeSeconds());
  absl::StatusOr<std::vector<StoredWorld>> mine = b->Load();
  ASSERT_TRUE(mine.ok()) << mine.status();
  EXPECT_THAT(*mine, SizeIs(3));
  adopted = b->Adopt();
  ASSERT_TRUE(adopted.ok());
  EXPECT_THAT(*adopted, IsEmpty());
  // a, restarted, takes a new lease and finds no worlds of its own.
  a.reset();
  std::unique_ptr<Store> a2 = Open(Node("a"));
  ASSERT_NE(a2, nullptr);
  absl::StatusOr<std::vector<StoredWorld>> a_worlds = a2->Load();
  ASSERT_TRUE(a_worlds.ok());
  EXPECT_THAT(*a_worlds, IsEmpty());
  EXPECT_TRUE(a2->Healthy().ok());
}

TEST_F(PostgresStoreTest, WritesToAWorldOfAnotherNodeAreRefusedNamingIt) {
  std::unique_ptr<Store> store = Open(Node("a"));
  ASSERT_NE(store, nullptr);
  ASSERT_TRUE(store->Append(Entry("t-1", 1)).ok());
  ASSERT_TRUE(store->Append(Entry("t-2", 1)).ok());
  // What an adoption by node b does to the world's row (here while a's lease holds, which
  // the lease check alone would not catch).
  ASSERT_TRUE(
      ExecForTesting(*store, "UPDATE journal_worlds SET owner = 'b' WHERE world_id = 't-1'")
          .ok());
  const absl::Status refused = store->Append(Entry("t-1", 2));
  EXPECT_EQ(refused.code(), absl::StatusCode::kUnavailable) << refused;
  EXPECT_THAT(refused.message(), HasSubstr("belongs to node b"));
  const absl::Status not_removed = store->Remove(Entry("t-1", 2));
  EXPECT_EQ(not_removed.code(), absl::StatusCode::kUnavailable) << not_removed;
  EXPECT_THAT(not_removed.message(), HasSubstr("belongs to node b"));
  // The node itself is fine, and so are its own worlds.
  EXPECT_TRUE(store->Healthy().ok());
  EXPECT_TRUE(store->Append(Entry("t-2", 2)).ok());
  absl::StatusOr<std::vector<StoredWorld>> mine = store->Load();
  ASSERT_TRUE(mine.ok()) << mine.status();
  ASSERT_THAT(*mine, SizeIs(1));
  EXPECT_EQ((*mine)[0].world_id, "t-2");
}

TEST_F(PostgresStoreTest, TheDatabaseGoingAwayFailsWritesAtOnceUntilItIsBack) {
  std::unique_ptr<Store> store = Open(Node("a", absl::Seconds(60)));
  ASSERT_NE(store, nullptr);
  ASSERT_TRUE(store->Append(Entry("t-1", 1)).ok());
  ASSERT_TRUE(cluster_->Stop().ok());
  const auto t0 = std::chrono::steady_clock::now();
  const absl::Status down = store->Append(Entry("t-1", 2));
  const double took_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(down.code(), absl::StatusCode::kUnavailable) << down;
  EXPECT_THAT(down.message(), HasSubstr("127.0.0.1"));
  EXPECT_LT(took_s, 2.0);
  EXPECT_EQ(store->Healthy().code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(store->Append(Entry("t-1", 2)).code(), absl::StatusCode::kUnavailable);

  ASSERT_TRUE(cluster_->Start().ok());
  // The clock persist reconnects: health comes back by itself.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!store->Healthy().ok() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_TRUE(store->Healthy().ok()) << store->Healthy();
  EXPECT_TRUE(store->Append(Entry("t-1", 2)).ok());
  absl::StatusOr<std::vector<StoredWorld>> worlds = store->Load();
  ASSERT_TRUE(worlds.ok()) << worlds.status();
  ASSERT_THAT(*worlds, SizeIs(1));
  EXPECT_THAT((*worlds)[0].entries, SizeIs(2));
}

TEST_F(PostgresStoreTest, ADatabaseThatDoesNotAnswerIsUnavailableAtOpen) {
  // A port nobody listens on: refused at once. The password never shows in a message.
  StoreOptions options = Node("a");
  options.postgres_uri = "postgresql://sportsim:secret@127.0.0.1:1/sportsim";
  const absl::Status s = Store::Open(options).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kUnavailable) << s;
  EXPECT_THAT(s.message(), HasSubstr("postgresql:127.0.0.1:1/sportsim node a"));
  EXPECT_THAT(s.message(), ::testing::Not(HasSubstr("secret")));
  options.postgres_uri = "postgresql://[bad";
  EXPECT_EQ(Store::Open(options).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace sportsim::server::store
