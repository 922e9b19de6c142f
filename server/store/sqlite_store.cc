// The journal of one node in a data directory: DIR/journal.db (SQLite, WAL, synchronous=FULL:
// a committed batch survives kill -9 and power loss) and DIR/LOCK (an exclusive flock holding
// the server's pid, so that a second server on the same directory refuses to start).
//
// Tables:
//   worlds(world_id, kind, last_index, anchor_tick, anchor_s)
//   entries(world_id, idx, tick, seat, type, body, anchor_s)   -- idx from 1, no gaps
//   checkpoints(world_id, idx, tick, state)
//   node_clock(id = 1, clock_s)
#include <fcntl.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/strip.h"
#include "server/store/group_commit.h"
#include "server/store/store_internal.h"

namespace sportsim::server::store {
namespace {

constexpr int kSchemaVersion = 1;
constexpr int kBusyTimeoutMs = 5000;

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS worlds (
  world_id TEXT PRIMARY KEY,
  kind TEXT NOT NULL,
  last_index INTEGER NOT NULL,
  anchor_tick INTEGER NOT NULL,
  anchor_s REAL NOT NULL
) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS entries (
  world_id TEXT NOT NULL,
  idx INTEGER NOT NULL,
  tick INTEGER NOT NULL,
  seat INTEGER NOT NULL,
  type INTEGER NOT NULL,
  body BLOB NOT NULL,
  anchor_s REAL NOT NULL,
  PRIMARY KEY (world_id, idx)
) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS checkpoints (
  world_id TEXT PRIMARY KEY,
  idx INTEGER NOT NULL,
  tick INTEGER NOT NULL,
  state BLOB NOT NULL
) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS node_clock (
  id INTEGER PRIMARY KEY CHECK (id = 1),
  clock_s REAL NOT NULL
);
INSERT OR IGNORE INTO node_clock (id, clock_s) VALUES (1, 0);
)sql";

/// The name of a primary result code, for messages ("SQLITE_FULL").
std::string_view CodeName(int rc) {
  switch (rc & 0xff) {
    case SQLITE_ERROR: return "SQLITE_ERROR";
    case SQLITE_PERM: return "SQLITE_PERM";
    case SQLITE_BUSY: return "SQLITE_BUSY";
    case SQLITE_LOCKED: return "SQLITE_LOCKED";
    case SQLITE_NOMEM: return "SQLITE_NOMEM";
    case SQLITE_READONLY: return "SQLITE_READONLY";
    case SQLITE_IOERR: return "SQLITE_IOERR";
    case SQLITE_CORRUPT: return "SQLITE_CORRUPT";
    case SQLITE_FULL: return "SQLITE_FULL";
    case SQLITE_CANTOPEN: return "SQLITE_CANTOPEN";
    case SQLITE_CONSTRAINT: return "SQLITE_CONSTRAINT";
    case SQLITE_NOTADB: return "SQLITE_NOTADB";
    default: return "SQLITE_?";
  }
}

/// A value bound to a statement's parameter.
struct Arg {
  enum class Type { kInt, kReal, kText, kBlob };
  Type type;
  int64_t i = 0;
  double d = 0.0;
  std::string_view s;

  Arg(int64_t v) : type(Type::kInt), i(v) {}                              // NOLINT
  Arg(uint64_t v) : type(Type::kInt), i(static_cast<int64_t>(v)) {}       // NOLINT
  Arg(int32_t v) : type(Type::kInt), i(v) {}                              // NOLINT
  Arg(uint32_t v) : type(Type::kInt), i(v) {}                             // NOLINT
  Arg(double v) : type(Type::kReal), d(v) {}                              // NOLINT
  Arg(std::string_view v) : type(Type::kText), s(v) {}                    // NOLINT
  Arg(const std::string& v) : type(Type::kText), s(v) {}                  // NOLINT
  static Arg Blob(std::string_view v) {
    Arg a(v);
    a.type = Type::kBlob;
    return a;
  }
};

std::string ColumnText(sqlite3_stmt* s, int col) {
  const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(s, col));
  return p == nullptr ? std::string() : std::string(p, sqlite3_column_bytes(s, col));
}
std::string ColumnBlob(sqlite3_stmt* s, int col) {
  const auto* p = static_cast<const char*>(sqlite3_column_blob(s, col));
  return p == nullptr ? std::string() : std::string(p, sqlite3_column_bytes(s, col));
}

class SqliteStore final : public GroupCommitStore, private CommitBackend {
 public:
  static absl::StatusOr<std::unique_ptr<Store>> Open(const StoreOptions& options);
  ~SqliteStore() override { Close(); }


  absl::StatusOr<std::vector<StoredWorld>> Load() override;
  absl::StatusOr<std::vector<StoredWorld>> Adopt() override {
    return std::vector<StoredWorld>();  // one node: nobody to adopt from
  }
  std::string Describe() const override { return "sqlite:" + path_; }
  void Close() override;

  absl::Status ExecForTesting(const std::string& sql) override {
    return writer_->Run([&]() { return Exec(sql.c_str()); });
  }

 private:
  SqliteStore(std::string dir, std::string path) : dir_(std::move(dir)), path_(std::move(path)) {}

  // CommitBackend.
  absl::Status CommitBatch(const std::vector<const JournalOp*>& ops,
                           std::vector<absl::Status>* results) override;
  absl::Status PersistClock(double clock_s, bool renew) override;
  absl::Status Fatal() const override { return absl::OkStatus(); }

  /// Close(), once: stops the writer, closes the database and releases the lock.
  void Shut();
  /// Takes DIR/LOCK or says who holds it.
  absl::Status Lock();
  /// Opens journal.db, sets WAL and synchronous=FULL, creates the schema, reads the clock.
  absl::Status OpenDatabase(double* clock0_s);
  /// One op of a batch: an error fails the batch; a refusal goes to `result`.
  absl::Status Apply(const JournalOp& op, absl::Status* result);

  /// The reason of a failed call, naming the database.
  std::string Reason(int rc) const;
  /// Runs SQL text without parameters (several statements).
  absl::Status Exec(const char* sql);
  /// Runs one statement (prepared once), calling `row` for each row; the rows changed.
  absl::StatusOr<int> Run(const char* sql, std::initializer_list<Arg> args,
                          const std::function<void(sqlite3_stmt*)>& row = nullptr);

  const std::string dir_;
  const std::string path_;  ///< DIR/journal.db
  int lock_fd_ = -1;
  sqlite3* db_ = nullptr;
  std::map<const char*, sqlite3_stmt*> statements_;  ///< by the SQL's address
  double clock0_s_ = 0.0;  ///< the node's clock as persisted before this Open
  std::once_flag closed_;
};

std::string SqliteStore::Reason(int rc) const {
  const char* msg = db_ != nullptr ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
  return absl::StrFormat("%s (%s)", msg, CodeName(rc));
}

absl::Status SqliteStore::Exec(const char* sql) {
  char* err = nullptr;
  const int rc = sqlite3_exec(db_, sql, nullptr, nullptr, &err);
  if (rc != SQLITE_OK) {
    std::string reason = absl::StrFormat("%s (%s)", err != nullptr ? err : sqlite3_errstr(rc),
                                         CodeName(rc));
    sqlite3_free(err);
    return absl::UnavailableError(
        absl::StrFormat("the journal %s failed: %s", Describe(), reason));
  }
  return absl::OkStatus();
}

absl::StatusOr<int> SqliteStore::Run(const char* sql, std::initializer_list<Arg> args,
                                     const std::function<void(sqlite3_stmt*)>& row) {
  sqlite3_stmt*& s = statements_[sql];
  if (s == nullptr) {
    const int rc = sqlite3_prepare_v3(db_, sql, -1, SQLITE_PREPARE_PERSISTENT, &s, nullptr);
    if (rc != SQLITE_OK) {
      return absl::InternalError(absl::StrFormat("the journal %s: cannot prepare %s: %s",
                                                 Describe(), sql, Reason(rc)));
    }
  }
  int i = 0;
  for (const Arg& a : args) {
    ++i;
    switch (a.type) {
      case Arg::Type::kInt: sqlite3_bind_int64(s, i, a.i); break;
      case Arg::Type::kReal: sqlite3_bind_double(s, i, a.d); break;
      case Arg::Type::kText:
        sqlite3_bind_text(s, i, a.s.data(), static_cast<int>(a.s.size()), SQLITE_STATIC);
        break;
      case Arg::Type::kBlob:
        // A null pointer would bind NULL: an empty blob is "".
        sqlite3_bind_blob(s, i, a.s.empty() ? "" : a.s.data(), static_cast<int>(a.s.size()),
                          SQLITE_STATIC);
        break;
    }
  }
  int rc;
  while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
    if (row) row(s);
  }
  sqlite3_reset(s);
  sqlite3_clear_bindings(s);
  if (rc != SQLITE_DONE) {
    return absl::UnavailableError(
        absl::StrFormat("the journal %s failed: %s", Describe(), Reason(rc)));
  }
  return sqlite3_changes(db_);
}

absl::Status SqliteStore::Lock() {
  const std::string lock_path = dir_ + "/LOCK";
  lock_fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "data_dir %s: cannot open its lock file %s: %s", dir_, lock_path, std::strerror(errno)));
  }
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    if (err != EWOULDBLOCK) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "data_dir %s: cannot lock %s: %s", dir_, lock_path, std::strerror(err)));
    }
    char buf[32] = {};
    const ssize_t n = ::pread(lock_fd_, buf, sizeof buf - 1, 0);
    std::string pid(buf, n > 0 ? static_cast<size_t>(n) : 0);
    pid = std::string(absl::StripAsciiWhitespace(pid));
    return absl::FailedPreconditionError(
        absl::StrFormat("data_dir %s is in use by another sportsim-server (pid %s)", dir_,
                        pid.empty() ? "unknown" : pid));
  }
  const std::string pid = absl::StrCat(::getpid(), "\n");
  if (::ftruncate(lock_fd_, 0) != 0 ||
      ::pwrite(lock_fd_, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size())) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "data_dir %s: cannot write %s: %s", dir_, lock_path, std::strerror(errno)));
  }
  return absl::OkStatus();
}

absl::Status SqliteStore::OpenDatabase(double* clock0_s) {
  auto unusable = [&](absl::string_view reason) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "data_dir %s: the journal %s is not usable: %s", dir_, path_, reason));
  };
  int rc = sqlite3_open_v2(path_.c_str(), &db_,
                           SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX,
                           nullptr);
  if (rc != SQLITE_OK) return unusable(Reason(rc));
  sqlite3_extended_result_codes(db_, 1);
  sqlite3_busy_timeout(db_, kBusyTimeoutMs);
  // WAL: a commit appends to the log and fsyncs it once; readers never block the writer.
  std::string mode;
  char* err = nullptr;
  rc = sqlite3_exec(
      db_, "PRAGMA journal_mode = WAL",
      [](void* out, int, char** values, char**) {
        *static_cast<std::string*>(out) = values[0] != nullptr ? values[0] : "";
        return 0;
      },
      &mode, &err);
  if (rc != SQLITE_OK) {
    std::string reason = absl::StrFormat("%s (%s)", err != nullptr ? err : sqlite3_errstr(rc),
                                         CodeName(rc));
    sqlite3_free(err);
    return unusable(reason);
  }
  if (mode != "wal") return unusable(absl::StrCat("cannot use WAL mode (got ", mode, ")"));
  // FULL: the log is fsynced at every commit, so a committed batch survives a power loss.
  if (absl::Status s = Exec("PRAGMA synchronous = FULL"); !s.ok()) return unusable(s.message());

  int version = 0;
  absl::StatusOr<int> read = Run("PRAGMA user_version", {}, [&](sqlite3_stmt* s) {
    version = sqlite3_column_int(s, 0);
  });
  if (!read.ok()) return unusable(read.status().message());
  if (version > kSchemaVersion) {
    return unusable(absl::StrFormat(
        "it was written by a newer sportsim-server (schema %d; this one knows %d)", version,
        kSchemaVersion));
  }
  const std::string schema = absl::StrCat("BEGIN IMMEDIATE;", kSchema, "PRAGMA user_version = ",
                                          kSchemaVersion, "; COMMIT;");
  if (absl::Status s = Exec(schema.c_str()); !s.ok()) {
    if (!sqlite3_get_autocommit(db_)) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    return unusable(s.message());
  }
  read = Run("SELECT clock_s FROM node_clock WHERE id = 1", {},
             [&](sqlite3_stmt* s) { *clock0_s = sqlite3_column_double(s, 0); });
  if (!read.ok()) return unusable(read.status().message());
  return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<Store>> SqliteStore::Open(const StoreOptions& options) {
  std::string dir = options.data_dir;
  while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    return absl::FailedPreconditionError(
        absl::StrFormat("data_dir %s cannot be created: %s", dir, ec.message()));
  }
  if (!std::filesystem::is_directory(dir, ec)) {
    return absl::FailedPreconditionError(
        absl::StrFormat("data_dir %s is not a directory", dir));
  }
  std::unique_ptr<SqliteStore> store(new SqliteStore(dir, dir + "/journal.db"));
  if (absl::Status s = store->Lock(); !s.ok()) return s;
  if (absl::Status s = store->OpenDatabase(&store->clock0_s_); !s.ok()) return s;
  store->writer_ = std::make_unique<GroupCommit>(
      static_cast<CommitBackend*>(store.get()), GroupCommitOptions{.name = store->Describe(),
                                      .clock0_s = store->clock0_s_,
                                      .clock_rate = options.clock_rate,
                                      .clock_interval = options.clock_interval});
  return std::unique_ptr<Store>(std::move(store));
}

void SqliteStore::Close() {
  std::call_once(closed_, [this] { Shut(); });
}

void SqliteStore::Shut() {
  if (writer_ != nullptr) writer_->Close();
  for (auto& [sql, s] : statements_) sqlite3_finalize(s);
  statements_.clear();
  if (db_ != nullptr) sqlite3_close(db_);
  db_ = nullptr;
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the flock
  lock_fd_ = -1;
}

absl::Status SqliteStore::Apply(const JournalOp& op, absl::Status* result) {
  const JournalEntry& e = op.entry;
  switch (op.type) {
    case JournalOp::Type::kAppend: {
      absl::StatusOr<int> changed;
      if (e.index == 1) {
        changed = Run(
            "INSERT INTO worlds (world_id, kind, last_index, anchor_tick, anchor_s) "
            "VALUES (?1, ?2, 1, ?3, ?4) ON CONFLICT (world_id) DO NOTHING",
            {e.world_id, e.kind, e.tick, e.anchor_s});
        if (!changed.ok()) return changed.status();
        if (*changed == 0) {
          *result = absl::AlreadyExistsError(absl::StrFormat(
              "journal entry 1 of %s: the world is already in the journal", e.world_id));
          return absl::OkStatus();
        }
      } else {
        // The entry must follow the world's last one: no gap, no duplicate.
        changed = Run(
            "UPDATE worlds SET last_index = ?2, anchor_tick = ?3, anchor_s = ?4 "
            "WHERE world_id = ?1 AND last_index = ?2 - 1",
            {e.world_id, e.index, e.tick, e.anchor_s});
        if (!changed.ok()) return changed.status();
        if (*changed == 0) {
          int64_t last = -1;
          absl::StatusOr<int> read =
              Run("SELECT last_index FROM worlds WHERE world_id = ?1", {e.world_id},
                  [&](sqlite3_stmt* s) { last = sqlite3_column_int64(s, 0); });
          if (!read.ok()) return read.status();
          *result = absl::InternalError(
              last < 0 ? absl::StrFormat("journal entry %d of %s: the world is not in the journal",
                                         e.index, e.world_id)
                       : absl::StrFormat("journal entry %d of %s: the journal's last entry of "
                                         "that world is %d (entries follow without gaps)",
                                         e.index, e.world_id, last));
          return absl::OkStatus();
        }
      }
      changed = Run(
          "INSERT INTO entries (world_id, idx, tick, seat, type, body, anchor_s) "
          "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
          {e.world_id, e.index, e.tick, e.seat, e.type, Arg::Blob(e.body), e.anchor_s});
      return changed.status();
    }
    case JournalOp::Type::kRemove: {
      for (const char* sql : {"DELETE FROM entries WHERE world_id = ?1",
                              "DELETE FROM checkpoints WHERE world_id = ?1",
                              "DELETE FROM worlds WHERE world_id = ?1"}) {
        if (absl::StatusOr<int> changed = Run(sql, {e.world_id}); !changed.ok()) {
          return changed.status();
        }
      }
      return absl::OkStatus();
    }
    case JournalOp::Type::kCheckpoint: {
      // Only for a world still in the journal that has reached `index`, and only forward.
      absl::StatusOr<int> changed = Run(
          "INSERT INTO checkpoints (world_id, idx, tick, state) "
          "SELECT world_id, ?2, ?3, ?4 FROM worlds WHERE world_id = ?1 AND last_index >= ?2 "
          "ON CONFLICT (world_id) DO UPDATE SET idx = excluded.idx, tick = excluded.tick, "
          "state = excluded.state WHERE excluded.idx > checkpoints.idx",
          {e.world_id, e.index, e.tick, Arg::Blob(e.body)});
      if (!changed.ok() || *changed == 0) return changed.status();
      // Compaction: the entries it covers go, except the creation (a restore needs it).
      return Run("DELETE FROM entries WHERE world_id = ?1 AND idx > 1 AND idx <= ?2",
                 {e.world_id, e.index})
          .status();
    }
    case JournalOp::Type::kAnchor:
      return Run("UPDATE worlds SET anchor_tick = ?2, anchor_s = ?3 WHERE world_id = ?1",
                 {e.world_id, e.tick, e.anchor_s})
          .status();
  }
  return absl::OkStatus();
}

absl::Status SqliteStore::CommitBatch(const std::vector<const JournalOp*>& ops,
                                      std::vector<absl::Status>* results) {
  auto failed = [&](const absl::Status& why) {
    // SQLite may have rolled back already (SQLITE_FULL, an I/O error); else nothing of the
    // batch may stay.
    if (!sqlite3_get_autocommit(db_)) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    return absl::UnavailableError(absl::StrFormat(
        "the journal %s could not commit: %s", Describe(),
        absl::StripPrefix(why.message(), absl::StrCat("the journal ", Describe(), " failed: "))));
  };
  if (absl::StatusOr<int> begun = Run("BEGIN IMMEDIATE", {}); !begun.ok()) {
    return failed(begun.status());
  }
  for (size_t i = 0; i < ops.size(); ++i) {
    if (absl::Status s = Apply(*ops[i], &(*results)[i]); !s.ok()) return failed(s);
  }
  if (absl::StatusOr<int> committed = Run("COMMIT", {}); !committed.ok()) {
    return failed(committed.status());
  }
  return absl::OkStatus();
}

absl::Status SqliteStore::PersistClock(double clock_s, bool /*renew*/) {
  // One statement: its own transaction, fsynced like any other.
  absl::StatusOr<int> changed = Run("UPDATE node_clock SET clock_s = ?1 WHERE id = 1", {clock_s});
  if (!changed.ok()) {
    return absl::UnavailableError(absl::StrFormat(
        "the journal %s cannot persist the node's clock: %s", Describe(),
        absl::StripPrefix(changed.status().message(),
                          absl::StrCat("the journal ", Describe(), " failed: "))));
  }
  return absl::OkStatus();
}

absl::StatusOr<std::vector<StoredWorld>> SqliteStore::Load() {
  std::vector<StoredWorld> worlds;
  absl::Status status = writer_->Run([&]() -> absl::Status {
    // One read transaction: the worlds and their entries as of one instant.
    if (absl::StatusOr<int> begun = Run("BEGIN", {}); !begun.ok()) return begun.status();
    std::map<std::string, size_t> at;
    absl::StatusOr<int> read = Run(
        "SELECT w.world_id, w.kind, w.anchor_tick, w.anchor_s, c.idx, c.tick, c.state "
        "FROM worlds w LEFT JOIN checkpoints c USING (world_id) ORDER BY w.world_id",
        {}, [&](sqlite3_stmt* s) {
          StoredWorld w;
          w.world_id = ColumnText(s, 0);
          w.kind = ColumnText(s, 1);
          w.anchor_tick = sqlite3_column_int64(s, 2);
          w.anchor_s = sqlite3_column_double(s, 3);
          if (sqlite3_column_type(s, 4) != SQLITE_NULL) {
            w.checkpoint_index = static_cast<uint64_t>(sqlite3_column_int64(s, 4));
            w.checkpoint_tick = sqlite3_column_int64(s, 5);
            w.checkpoint = ColumnBlob(s, 6);
          }
          at[w.world_id] = worlds.size();
          worlds.push_back(std::move(w));
        });
    if (read.ok()) {
      read = Run(
          "SELECT world_id, idx, tick, seat, type, body, anchor_s FROM entries "
          "ORDER BY world_id, idx",
          {}, [&](sqlite3_stmt* s) {
            auto it = at.find(ColumnText(s, 0));
            if (it == at.end()) return;  // entries of no world: not restorable, not returned
            StoredWorld& w = worlds[it->second];
            w.entries.push_back(JournalEntry{
                .world_id = w.world_id,
                .kind = w.kind,
                .index = static_cast<uint64_t>(sqlite3_column_int64(s, 1)),
                .tick = sqlite3_column_int64(s, 2),
                .seat = sqlite3_column_int(s, 3),
                .type = static_cast<uint32_t>(sqlite3_column_int64(s, 4)),
                .body = ColumnBlob(s, 5),
                .anchor_s = sqlite3_column_double(s, 6)});
          });
    }
    Run("COMMIT", {}).IgnoreError();
    return read.status();
  });
  if (!status.ok()) return status;
  for (StoredWorld& w : worlds) w.clock_s = clock0_s_;
  return worlds;
}

}  // namespace

absl::StatusOr<std::unique_ptr<Store>> OpenSqlite(const StoreOptions& options) {
  return SqliteStore::Open(options);
}

}  // namespace sportsim::server::store
