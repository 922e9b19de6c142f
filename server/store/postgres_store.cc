// The journal of a fleet of nodes in one PostgreSQL database, with leases.
//
// Tables (created if missing, under an advisory lock so that nodes starting together do not
// race):
//   journal_nodes(name, epoch, expires_at, clock_s)        -- one row per node: its lease
//   journal_worlds(world_id, kind, owner, last_index, anchor_tick, anchor_s)
//   journal_entries(world_id, idx, tick, seat, type, body, anchor_s)
//   journal_checkpoints(world_id, idx, tick, state)
//
// Leases. Open bumps this node's epoch (fencing any previous process of the same node) and
// sets expires_at = now() + lease; the writer renews it every lease / 3 along with the clock.
// Every write transaction first checks, with the database's clock, that this node still holds
// its lease at its epoch (and locks that row, so that no Adopt can take the node's worlds
// until the transaction ends), and every write names the world's owner. A node whose check
// fails has lost its lease for good: it must restart to take a new one. Adopt() takes the
// worlds of nodes whose lease lapsed, bumping their epochs in the same transaction.
//
// Every statement is parameterized (PQexecParams / PQsendQueryParams, binary parameters and
// results; bodies are bytea). A write batch is one pipeline, one round trip: BEGIN, the lease
// check (journal_hold_lease), one statement per write, COMMIT. A lost connection fails the
// batch at once (UNAVAILABLE); the writer reconnects on a later batch or clock persist.
// Connections carry connect_timeout, TCP keepalives, tcp_user_timeout and statement_timeout,
// so that a database that vanishes never hangs a write for long (the URI may override them).
#include <endian.h>
#include <libpq-fe.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "server/store/group_commit.h"
#include "server/store/store_internal.h"

namespace sportsim::server::store {
namespace {

// Type OIDs of the parameters (pg_type.h is a server header).
constexpr Oid kInt4 = 23;
constexpr Oid kInt8 = 20;
constexpr Oid kFloat8 = 701;
constexpr Oid kText = 25;
constexpr Oid kBytea = 17;

// The advisory lock that serializes creating the schema ("sportsim" in ASCII).
constexpr int64_t kSchemaLock = 0x73706f727473696d;

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS journal_nodes (
  name text PRIMARY KEY,
  epoch bigint NOT NULL,
  expires_at timestamptz NOT NULL,
  clock_s double precision NOT NULL DEFAULT 0
);
CREATE TABLE IF NOT EXISTS journal_worlds (
  world_id text PRIMARY KEY,
  kind text NOT NULL,
  owner text NOT NULL,
  last_index bigint NOT NULL,
  anchor_tick bigint NOT NULL,
  anchor_s double precision NOT NULL
);
CREATE INDEX IF NOT EXISTS journal_worlds_owner ON journal_worlds (owner);
CREATE TABLE IF NOT EXISTS journal_entries (
  world_id text NOT NULL,
  idx bigint NOT NULL,
  tick bigint NOT NULL,
  seat integer NOT NULL,
  type bigint NOT NULL,
  body bytea NOT NULL,
  anchor_s double precision NOT NULL,
  PRIMARY KEY (world_id, idx)
);
CREATE TABLE IF NOT EXISTS journal_checkpoints (
  world_id text PRIMARY KEY,
  idx bigint NOT NULL,
  tick bigint NOT NULL,
  state bytea NOT NULL
);
-- The first statement of every write batch: fails the transaction unless the node still holds
-- its lease at its epoch by the database's clock, and locks the node's row until it ends.
CREATE OR REPLACE FUNCTION journal_hold_lease(node text, node_epoch bigint) RETURNS void
LANGUAGE plpgsql AS $$
BEGIN
  PERFORM 1 FROM journal_nodes
    WHERE name = node AND epoch = node_epoch AND expires_at > now() FOR SHARE;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'node % lost its lease (epoch %)', node, node_epoch
      USING ERRCODE = 'SP001';
  END IF;
END $$;
)sql";

// The SQLSTATE journal_hold_lease raises.
constexpr std::string_view kLeaseLost = "SP001";
// A pipelined batch asks the server for its results every this many statements, so that
// neither side's socket buffer fills while the other waits.
constexpr size_t kPipelineChunk = 512;

// How long to wait for the database: connecting, a statement, an unanswered TCP peer.
constexpr const char* kConnectTimeoutS = "5";
constexpr const char* kStatementTimeoutMs = "10000";
constexpr const char* kTcpUserTimeoutMs = "10000";

/// A bound parameter, sent in binary.
class Param {
 public:
  Param(int64_t v) : type_(kInt8) { Put64(static_cast<uint64_t>(v)); }               // NOLINT
  Param(uint64_t v) : type_(kInt8) { Put64(v); }                                     // NOLINT
  Param(uint32_t v) : type_(kInt8) { Put64(v); }                                     // NOLINT
  Param(int32_t v) : type_(kInt4) {                                                  // NOLINT
    const uint32_t be = htobe32(static_cast<uint32_t>(v));
    std::memcpy(buf_, &be, 4);
    size_ = 4;
  }
  Param(double v) : type_(kFloat8) {                                                 // NOLINT
    uint64_t bits;
    std::memcpy(&bits, &v, 8);
    Put64(bits);
  }
  Param(const std::string& v) : type_(kText), view_(v) {}                            // NOLINT
  static Param Bytea(std::string_view v) { return Param(kBytea, v); }

  Oid type() const { return type_; }
  const char* data() const { return view_.data() != nullptr ? view_.data() : buf_; }
  int size() const { return view_.data() != nullptr ? static_cast<int>(view_.size()) : size_; }

 private:
  Param(Oid type, std::string_view v) : type_(type), view_(v) {}
  void Put64(uint64_t v) {
    const uint64_t be = htobe64(v);
    std::memcpy(buf_, &be, 8);
    size_ = 8;
  }
  Oid type_;
  std::string_view view_;  // text and bytea: the caller's bytes (alive during the call)
  char buf_[8] = {};
  int size_ = 0;
};

struct ResultDeleter {
  void operator()(PGresult* r) const { PQclear(r); }
};
using Result = std::unique_ptr<PGresult, ResultDeleter>;

// Binary results.
int64_t Int8(const PGresult* r, int row, int col) {
  uint64_t be;
  std::memcpy(&be, PQgetvalue(r, row, col), 8);
  return static_cast<int64_t>(be64toh(be));
}
int32_t Int4(const PGresult* r, int row, int col) {
  uint32_t be;
  std::memcpy(&be, PQgetvalue(r, row, col), 4);
  return static_cast<int32_t>(be32toh(be));
}
double Float8(const PGresult* r, int row, int col) {
  const uint64_t bits = static_cast<uint64_t>(Int8(r, row, col));
  double v;
  std::memcpy(&v, &bits, 8);
  return v;
}
std::string Bytes(const PGresult* r, int row, int col) {
  return std::string(PQgetvalue(r, row, col), PQgetlength(r, row, col));
}
/// Rows a command changed (INSERT, UPDATE, DELETE).
int64_t Changed(const PGresult* r) {
  const char* n = PQcmdTuples(const_cast<PGresult*>(r));
  return n == nullptr || *n == '\0' ? 0 : std::atoll(n);
}

/// One statement of a pipelined batch.
struct Statement {
  const char* sql;
  std::vector<Param> params;
};

/// libpq's messages end in a newline and may run over several lines ("...\n\tIs the server
/// running...?"): one line, the lines joined by "; ".
std::string Clean(const char* msg) {
  std::string out;
  bool newline = false;
  for (const char* p = msg != nullptr ? msg : ""; *p != '\0'; ++p) {
    if (*p == '\n') {
      newline = true;
    } else if (newline && (*p == '\t' || *p == ' ')) {
      continue;
    } else {
      if (newline && !out.empty()) out += "; ";
      newline = false;
      out += *p;
    }
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out.empty() ? "unknown error" : out;
}

class PostgresStore final : public GroupCommitStore, private CommitBackend {
 public:
  static absl::StatusOr<std::unique_ptr<Store>> Open(const StoreOptions& options);
  ~PostgresStore() override { Close(); }


  absl::StatusOr<std::vector<StoredWorld>> Load() override;
  absl::StatusOr<std::vector<StoredWorld>> Adopt() override;
  std::string Describe() const override { return describe_; }
  void Close() override {
    std::call_once(closed_, [this] { Shut(); });
  }

  absl::Status ExecForTesting(const std::string& sql) override {
    return writer_->Run([&]() -> absl::Status {
      if (absl::Status s = Connected(/*probe=*/true); !s.ok()) return s;
      return Exec(sql.c_str(), {}).status();
    });
  }

 private:
  PostgresStore(const StoreOptions& options, std::string server)
      : options_(options),
        server_(std::move(server)),
        describe_(absl::StrFormat("postgresql:%s node %s", server_, options.node)) {}

  // CommitBackend.
  absl::Status CommitBatch(const std::vector<const JournalOp*>& ops,
                           std::vector<absl::Status>* results) override;
  absl::Status PersistClock(double clock_s, bool renew) override;
  absl::Status Fatal() const override {
    std::lock_guard<std::mutex> lock(fatal_mu_);
    return fatal_;
  }

  void Shut();
  /// Connects (Open) or reconnects; UNAVAILABLE naming the server and the reason.
  absl::Status Connect();
  /// OK when the connection is up, else reconnects: always when `probe` (the clock persist,
  /// Load, Adopt), else only when the last attempt is older than a clock interval, so that
  /// writes fail at once while the database is down.
  absl::Status Connected(bool probe);
  /// Creates the tables if missing, under the advisory lock.
  absl::Status CreateSchema();
  /// Takes this node's lease: epoch + 1, expires_at = now() + lease; reads the clock.
  absl::Status TakeLease();

  /// Runs one statement; UNAVAILABLE with the database's reason when it fails.
  absl::StatusOr<Result> Exec(const char* sql, const std::vector<Param>& params);
  /// Sends `statements` in one pipeline (one round trip) ending in a sync, and reads one
  /// result for each into `out`. False when the connection broke meanwhile (`out` is then
  /// incomplete and the outcome unknown); the connection is then dropped.
  bool Pipeline(const std::vector<Statement>& statements, std::vector<Result>* out);
  /// Closes a broken connection (Connected() makes a new one), keeping its last message.
  void Drop();
  /// UNAVAILABLE "the journal ... could not <doing>: <reason>".
  absl::Status Failed(std::string_view doing, const absl::Status& why) const;
  /// ROLLBACK when a transaction may be open on a live connection.
  void Rollback();

  /// Inside a transaction: this node still holds its lease at its epoch (its row locked until
  /// the transaction ends). Sets fatal_ and returns it when not.
  absl::Status CheckLease();
  /// Sets fatal_ ("lost its lease") with what the database says about the node now.
  absl::Status LoseLease();
  /// The statement that applies one op of a batch. An append or a removal that is refused
  /// (not this node's world, an index out of turn) changes nothing: its statement reports no
  /// row changed (Changed()).
  Statement OpStatement(const JournalOp& op) const;
  /// Why an append or a removal that changed nothing was refused, read after the batch
  /// committed: its world's owner or its last index (OK: a removal of a world already gone).
  absl::Status Refusal(const JournalOp& op);
  /// The worlds `owner` holds, with `clock_s` (inside a transaction).
  absl::Status LoadOwner(const std::string& owner, double clock_s,
                         std::vector<StoredWorld>* out);

  const StoreOptions options_;
  const std::string server_;    ///< "host:port/db", no password
  const std::string describe_;  ///< Describe()
  PGconn* conn_ = nullptr;      ///< used on the writer thread only (and by Open before it)
  absl::Time last_connect_ = absl::InfinitePast();  ///< the last reconnect attempt
  std::string last_error_;      ///< why the connection was dropped
  int64_t epoch_ = 0;           ///< this node's lease
  double clock0_s_ = 0.0;       ///< the node's clock as persisted before this Open
  mutable std::mutex fatal_mu_;
  absl::Status fatal_;          ///< the lease is lost (for good)
  std::once_flag closed_;
};

absl::Status PostgresStore::Connect() {
  last_connect_ = absl::Now();
  if (conn_ != nullptr) {
    PQreset(conn_);
  } else {
    // Our defaults first: what the URI says overrides them (expand_dbname).
    const std::string pg_options = absl::StrCat("-c statement_timeout=", kStatementTimeoutMs,
                                                " -c client_min_messages=warning");
    const char* keys[] = {"connect_timeout",  "keepalives",          "keepalives_idle",
                          "keepalives_interval", "keepalives_count", "tcp_user_timeout",
                          "application_name", "options",             "dbname",
                          nullptr};
    const char* values[] = {kConnectTimeoutS, "1",
                            "5",              "2",
                            "3",              kTcpUserTimeoutMs,
                            "sportsim-server", pg_options.c_str(),
                            options_.postgres_uri.c_str(), nullptr};
    conn_ = PQconnectdbParams(keys, values, /*expand_dbname=*/1);
    if (conn_ != nullptr) PQsetNoticeProcessor(conn_, [](void*, const char*) {}, nullptr);
  }
  if (conn_ == nullptr) {
    return absl::UnavailableError("the database is unreachable: out of memory");
  }
  if (PQstatus(conn_) != CONNECTION_OK) {
    return absl::UnavailableError(
        absl::StrCat("the database is unreachable: ", Clean(PQerrorMessage(conn_))));
  }
  return absl::OkStatus();
}

absl::Status PostgresStore::Connected(bool probe) {
  // Reading what is pending finds a connection the server closed meanwhile (it restarted)
  // without a round trip, before a batch is sent over it.
  if (conn_ != nullptr && PQstatus(conn_) == CONNECTION_OK && PQconsumeInput(conn_) == 1 &&
      PQstatus(conn_) == CONNECTION_OK) {
    return absl::OkStatus();
  }
  if (conn_ != nullptr && PQstatus(conn_) != CONNECTION_OK) last_error_ = Clean(PQerrorMessage(conn_));
  if (!probe && absl::Now() - last_connect_ < options_.clock_interval) {
    return absl::UnavailableError(absl::StrCat("the database is unreachable: ", last_error_));
  }
  return Connect();
}

void PostgresStore::Drop() {
  if (conn_ == nullptr) return;
  last_error_ = Clean(PQerrorMessage(conn_));
  PQfinish(conn_);
  conn_ = nullptr;
}

bool PostgresStore::Pipeline(const std::vector<Statement>& statements,
                             std::vector<Result>* out) {
  out->clear();
  if (PQenterPipelineMode(conn_) != 1) return false;
  // One result per statement, then the null that ends that statement's results.
  auto read_one = [&]() {
    Result r(PQgetResult(conn_));
    if (r == nullptr || PQstatus(conn_) != CONNECTION_OK) return false;
    out->push_back(std::move(r));
    Result end(PQgetResult(conn_));
    return end == nullptr;
  };
  auto broken = [&]() {
    Drop();
    return false;
  };
  for (size_t i = 0; i < statements.size(); ++i) {
    const Statement& st = statements[i];
    std::vector<Oid> types;
    std::vector<const char*> values;
    std::vector<int> lengths;
    std::vector<int> formats(st.params.size(), 1);
    for (const Param& p : st.params) {
      types.push_back(p.type());
      values.push_back(p.data());
      lengths.push_back(p.size());
    }
    if (PQsendQueryParams(conn_, st.sql, static_cast<int>(st.params.size()), types.data(),
                          values.data(), lengths.data(), formats.data(),
                          /*resultFormat=*/1) != 1) {
      return broken();
    }
    if ((i + 1) % kPipelineChunk == 0) {
      if (PQsendFlushRequest(conn_) != 1 || PQflush(conn_) != 0) return broken();
      while (out->size() <= i) {
        if (!read_one()) return broken();
      }
    }
  }
  if (PQpipelineSync(conn_) != 1) return broken();
  while (out->size() < statements.size()) {
    if (!read_one()) return broken();
  }
  Result sync(PQgetResult(conn_));
  if (sync == nullptr || PQresultStatus(sync.get()) != PGRES_PIPELINE_SYNC) return broken();
  return PQexitPipelineMode(conn_) == 1 || broken();
}

absl::StatusOr<Result> PostgresStore::Exec(const char* sql, const std::vector<Param>& params) {
  std::vector<Oid> types;
  std::vector<const char*> values;
  std::vector<int> lengths;
  std::vector<int> formats;
  for (const Param& p : params) {
    types.push_back(p.type());
    values.push_back(p.data());
    lengths.push_back(p.size());
    formats.push_back(1);
  }
  Result r(PQexecParams(conn_, sql, static_cast<int>(params.size()), types.data(),
                        values.data(), lengths.data(), formats.data(), /*resultFormat=*/1));
  const ExecStatusType status = r != nullptr ? PQresultStatus(r.get()) : PGRES_FATAL_ERROR;
  if (status == PGRES_COMMAND_OK || status == PGRES_TUPLES_OK) return r;
  std::string reason = Clean(r != nullptr ? PQresultErrorMessage(r.get()) : "");
  if (reason == "unknown error") reason = Clean(PQerrorMessage(conn_));
  if (PQstatus(conn_) != CONNECTION_OK) {
    return absl::UnavailableError(absl::StrCat("the database is unreachable: ", reason));
  }
  return absl::UnavailableError(reason);
}

absl::Status PostgresStore::Failed(std::string_view doing, const absl::Status& why) const {
  return absl::UnavailableError(
      absl::StrFormat("the journal %s could not %s: %s", describe_, doing, why.message()));
}

void PostgresStore::Rollback() {
  if (conn_ != nullptr && PQstatus(conn_) == CONNECTION_OK &&
      PQtransactionStatus(conn_) != PQTRANS_IDLE) {
    Result r(PQexec(conn_, "ROLLBACK"));
  }
}

absl::Status PostgresStore::CreateSchema() {
  absl::StatusOr<Result> r = Exec("BEGIN", {});
  if (r.ok()) r = Exec("SELECT pg_advisory_xact_lock($1)", {kSchemaLock});
  if (r.ok()) {
    // Several statements: the simple protocol (no parameters).
    Result created(PQexec(conn_, kSchema));
    if (PQresultStatus(created.get()) != PGRES_COMMAND_OK) {
      r = absl::FailedPreconditionError(Clean(PQresultErrorMessage(created.get())));
    }
  }
  if (r.ok()) r = Exec("COMMIT", {});
  if (!r.ok()) {
    Rollback();
    return absl::FailedPreconditionError(
        absl::StrFormat("the journal %s cannot create its tables: %s", describe_,
                        r.status().message()));
  }
  return absl::OkStatus();
}

absl::Status PostgresStore::TakeLease() {
  absl::StatusOr<Result> r = Exec(
      "INSERT INTO journal_nodes (name, epoch, expires_at, clock_s) "
      "VALUES ($1, 1, now() + $2 * interval '1 second', 0) "
      "ON CONFLICT (name) DO UPDATE SET epoch = journal_nodes.epoch + 1, "
      "expires_at = EXCLUDED.expires_at "
      "RETURNING epoch, clock_s",
      {options_.node, absl::ToDoubleSeconds(options_.lease)});
  if (!r.ok()) {
    return absl::UnavailableError(absl::StrFormat(
        "the journal %s cannot take the node's lease: %s", describe_, r.status().message()));
  }
  epoch_ = Int8(r->get(), 0, 0);
  clock0_s_ = Float8(r->get(), 0, 1);
  return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<Store>> PostgresStore::Open(const StoreOptions& options) {
  // The server as logs may show it: host, port and database, never the password.
  char* err = nullptr;
  PQconninfoOption* parsed = PQconninfoParse(options.postgres_uri.c_str(), &err);
  if (parsed == nullptr) {
    std::string reason = Clean(err);
    PQfreemem(err);
    return absl::InvalidArgumentError(
        absl::StrFormat("postgres_uri does not parse: %s", reason));
  }
  std::map<std::string, std::string> given;
  for (PQconninfoOption* o = parsed; o->keyword != nullptr; ++o) {
    if (o->val != nullptr && *o->val != '\0') given[o->keyword] = o->val;
  }
  PQconninfoFree(parsed);
  auto value = [&](const char* key, std::string fallback) {
    auto it = given.find(key);
    return it != given.end() ? it->second : fallback;
  };
  const std::string host = value("host", value("hostaddr", "localhost"));
  const std::string server = absl::StrFormat("%s:%s/%s", host, value("port", "5432"),
                                             value("dbname", value("user", "postgres")));

  std::unique_ptr<PostgresStore> store(new PostgresStore(options, server));
  if (absl::Status s = store->Connect(); !s.ok()) {
    return absl::UnavailableError(absl::StrFormat("the journal %s cannot open: %s",
                                                  store->describe_, s.message()));
  }
  if (absl::Status s = store->CreateSchema(); !s.ok()) return s;
  if (absl::Status s = store->TakeLease(); !s.ok()) return s;
  store->writer_ = std::make_unique<GroupCommit>(
      static_cast<CommitBackend*>(store.get()), GroupCommitOptions{.name = store->describe_,
                                      .clock0_s = store->clock0_s_,
                                      .clock_rate = options.clock_rate,
                                      .clock_interval = options.clock_interval,
                                      .renew_interval = options.lease / 3});
  return std::unique_ptr<Store>(std::move(store));
}

void PostgresStore::Shut() {
  if (writer_ != nullptr) writer_->Close();
  if (conn_ != nullptr) PQfinish(conn_);
  conn_ = nullptr;
}

absl::Status PostgresStore::LoseLease() {
  std::string now;
  absl::StatusOr<Result> r = Exec(
      "SELECT epoch, expires_at <= now() FROM journal_nodes WHERE name = $1", {options_.node});
  if (r.ok() && PQntuples(r->get()) == 1) {
    const int64_t epoch = Int8(r->get(), 0, 0);
    const bool expired = *PQgetvalue(r->get(), 0, 1) != 0;
    if (epoch != epoch_) {
      now = absl::StrFormat("node %s is at epoch %d now (another process took the node over, "
                            "or another node adopted its worlds)",
                            options_.node, epoch);
    } else if (expired) {
      now = "its lease expired before it was renewed";
    }
  }
  std::lock_guard<std::mutex> lock(fatal_mu_);
  if (fatal_.ok()) {
    fatal_ = absl::UnavailableError(absl::StrFormat(
        "the journal %s: this node lost its lease (epoch %d)%s%s; restart the server to take a "
        "new one",
        describe_, epoch_, now.empty() ? "" : ": ", now));
  }
  return fatal_;
}

absl::Status PostgresStore::CheckLease() {
  absl::StatusOr<Result> r = Exec(
      "SELECT 1 FROM journal_nodes WHERE name = $1 AND epoch = $2 AND expires_at > now() "
      "FOR SHARE",
      {options_.node, epoch_});
  if (!r.ok()) return r.status();
  if (PQntuples(r->get()) == 1) return absl::OkStatus();
  absl::Status lost = LoseLease();
  Rollback();
  return lost;
}

Statement PostgresStore::OpStatement(const JournalOp& op) const {
  const JournalEntry& e = op.entry;
  switch (op.type) {
    case JournalOp::Type::kAppend:
      if (e.index == 1) {
        return Statement{
            "WITH w AS (INSERT INTO journal_worlds "
            "(world_id, kind, owner, last_index, anchor_tick, anchor_s) "
            "VALUES ($1, $2, $3, 1, $4, $7) ON CONFLICT (world_id) DO NOTHING "
            "RETURNING world_id) "
            "INSERT INTO journal_entries (world_id, idx, tick, seat, type, body, anchor_s) "
            "SELECT world_id, 1, $4, $5, $6, $8, $7 FROM w",
            {e.world_id, e.kind, options_.node, e.tick, e.seat, e.type, e.anchor_s,
             Param::Bytea(e.body)}};
      }
      // Only the world's owner, and only the entry after its last one (no gap, no
      // duplicate): the world row is checked and moved on in the same statement.
      return Statement{
          "WITH w AS (UPDATE journal_worlds SET last_index = $2, anchor_tick = $3, "
          "anchor_s = $7 WHERE world_id = $1 AND owner = $8 AND last_index = $2 - 1 "
          "RETURNING world_id) "
          "INSERT INTO journal_entries (world_id, idx, tick, seat, type, body, anchor_s) "
          "SELECT world_id, $2, $3, $4, $5, $6, $7 FROM w",
          {e.world_id, e.index, e.tick, e.seat, e.type, Param::Bytea(e.body), e.anchor_s,
           options_.node}};
    case JournalOp::Type::kRemove:
      return Statement{
          "WITH w AS (DELETE FROM journal_worlds WHERE world_id = $1 AND owner = $2 "
          "RETURNING world_id), "
          "e AS (DELETE FROM journal_entries WHERE world_id IN (SELECT world_id FROM w)), "
          "c AS (DELETE FROM journal_checkpoints WHERE world_id IN (SELECT world_id FROM w)) "
          "SELECT count(*) FROM w",
          {e.world_id, options_.node}};
    case JournalOp::Type::kCheckpoint:
      // Only for this node's world that has reached `index`, only forward; the entries it
      // covers go in the same statement, except the creation (a restore needs it).
      return Statement{
          "WITH w AS (SELECT world_id FROM journal_worlds WHERE world_id = $1 "
          "AND owner = $5 AND last_index >= $2), "
          "c AS (INSERT INTO journal_checkpoints (world_id, idx, tick, state) "
          "SELECT world_id, $2, $3, $4 FROM w ON CONFLICT (world_id) DO UPDATE SET "
          "idx = EXCLUDED.idx, tick = EXCLUDED.tick, state = EXCLUDED.state "
          "WHERE journal_checkpoints.idx < EXCLUDED.idx RETURNING idx) "
          "DELETE FROM journal_entries WHERE world_id = $1 AND idx > 1 "
          "AND idx <= (SELECT idx FROM c)",
          {e.world_id, e.index, e.tick, Param::Bytea(e.body), options_.node}};
    case JournalOp::Type::kAnchor:
      return Statement{
          "UPDATE journal_worlds SET anchor_tick = $2, anchor_s = $3 "
          "WHERE world_id = $1 AND owner = $4",
          {e.world_id, e.tick, e.anchor_s, options_.node}};
  }
  return Statement{"SELECT 1", {}};
}

absl::Status PostgresStore::Refusal(const JournalOp& op) {
  const JournalEntry& e = op.entry;
  const std::string what = op.type == JournalOp::Type::kRemove
                               ? std::string("the deletion")
                               : absl::StrFormat("journal entry %d", e.index);
  absl::StatusOr<Result> r = Exec(
      "SELECT owner, last_index FROM journal_worlds WHERE world_id = $1", {e.world_id});
  if (!r.ok()) {
    return absl::UnavailableError(absl::StrFormat("%s of %s was refused (%s)", what,
                                                  e.world_id, r.status().message()));
  }
  if (PQntuples(r->get()) == 0) {
    if (op.type == JournalOp::Type::kRemove) return absl::OkStatus();  // already gone
    return absl::InternalError(
        absl::StrFormat("%s of %s: the world is not in the journal", what, e.world_id));
  }
  const std::string owner = Bytes(r->get(), 0, 0);
  if (owner != options_.node) {
    return absl::UnavailableError(
        absl::StrFormat("%s of %s: the world now belongs to node %s (this node is %s)", what,
                        e.world_id, owner, options_.node));
  }
  if (e.index == 1) {
    return absl::AlreadyExistsError(
        absl::StrFormat("%s of %s: the world is already in the journal", what, e.world_id));
  }
  return absl::InternalError(absl::StrFormat(
      "%s of %s: the journal's last entry of that world is %d (entries follow without gaps)",
      what, e.world_id, Int8(r->get(), 0, 1)));
}

absl::Status PostgresStore::CommitBatch(const std::vector<const JournalOp*>& ops,
                                        std::vector<absl::Status>* results) {
  if (absl::Status s = Connected(/*probe=*/false); !s.ok()) return Failed("commit", s);
  // The whole batch in one round trip: the lease first, each op, COMMIT. The first error
  // fails the transaction, and the statements after it are skipped.
  std::vector<Statement> statements;
  statements.reserve(ops.size() + 3);
  statements.push_back(Statement{"BEGIN", {}});
  statements.push_back(
      Statement{"SELECT journal_hold_lease($1, $2)", {options_.node, epoch_}});
  for (const JournalOp* op : ops) statements.push_back(OpStatement(*op));
  statements.push_back(Statement{"COMMIT", {}});
  std::vector<Result> out;
  if (!Pipeline(statements, &out)) {
    return Failed("commit", absl::UnavailableError(
                                absl::StrCat("the database is unreachable: ", last_error_)));
  }
  for (size_t i = 0; i < out.size(); ++i) {
    const ExecStatusType status = PQresultStatus(out[i].get());
    if (status == PGRES_COMMAND_OK || status == PGRES_TUPLES_OK) continue;
    const char* state = PQresultErrorField(out[i].get(), PG_DIAG_SQLSTATE);
    const std::string reason = Clean(PQresultErrorMessage(out[i].get()));
    Rollback();
    if (i == 1 && state != nullptr && state == kLeaseLost) return LoseLease();
    return Failed("commit", absl::UnavailableError(reason));
  }
  // COMMIT of a transaction that failed answers ROLLBACK.
  if (std::string_view(PQcmdStatus(out.back().get())) != "COMMIT") {
    return Failed("commit", absl::AbortedError("the transaction was rolled back"));
  }
  // The appends and removals that changed nothing were refused: say why.
  for (size_t i = 0; i < ops.size(); ++i) {
    const PGresult* r = out[i + 2].get();
    switch (ops[i]->type) {
      case JournalOp::Type::kAppend:
        if (Changed(r) == 0) (*results)[i] = Refusal(*ops[i]);
        break;
      case JournalOp::Type::kRemove:
        if (Int8(r, 0, 0) == 0) (*results)[i] = Refusal(*ops[i]);
        break;
      default:
        break;  // checkpoints and anchors of worlds that are not this node's: ignored
    }
  }
  return absl::OkStatus();
}

absl::Status PostgresStore::PersistClock(double clock_s, bool renew) {
  if (absl::Status s = Connected(/*probe=*/true); !s.ok()) {
    return Failed("persist the node's clock", s);
  }
  // One statement, its own transaction; only while the lease holds.
  absl::StatusOr<Result> r =
      renew ? Exec("UPDATE journal_nodes SET clock_s = $3, "
                   "expires_at = now() + $4 * interval '1 second' "
                   "WHERE name = $1 AND epoch = $2 AND expires_at > now()",
                   {options_.node, epoch_, clock_s, absl::ToDoubleSeconds(options_.lease)})
            : Exec("UPDATE journal_nodes SET clock_s = $3 "
                   "WHERE name = $1 AND epoch = $2 AND expires_at > now()",
                   {options_.node, epoch_, clock_s});
  if (!r.ok()) return Failed("persist the node's clock", r.status());
  if (Changed(r->get()) == 0) return LoseLease();
  return absl::OkStatus();
}

absl::Status PostgresStore::LoadOwner(const std::string& owner, double clock_s,
                                      std::vector<StoredWorld>* out) {
  absl::StatusOr<Result> worlds = Exec(
      "SELECT w.world_id, w.kind, w.anchor_tick, w.anchor_s, c.idx, c.tick, c.state "
      "FROM journal_worlds w LEFT JOIN journal_checkpoints c USING (world_id) "
      "WHERE w.owner = $1 ORDER BY w.world_id COLLATE \"C\"",
      {owner});
  if (!worlds.ok()) return worlds.status();
  absl::StatusOr<Result> entries = Exec(
      "SELECT e.world_id, e.idx, e.tick, e.seat, e.type, e.body, e.anchor_s "
      "FROM journal_entries e JOIN journal_worlds w USING (world_id) "
      "WHERE w.owner = $1 ORDER BY e.world_id COLLATE \"C\", e.idx",
      {owner});
  if (!entries.ok()) return entries.status();
  const PGresult* wr = worlds->get();
  const PGresult* er = entries->get();
  const int n_entries = PQntuples(er);
  int j = 0;
  for (int i = 0; i < PQntuples(wr); ++i) {
    StoredWorld w;
    w.world_id = Bytes(wr, i, 0);
    w.kind = Bytes(wr, i, 1);
    w.anchor_tick = Int8(wr, i, 2);
    w.anchor_s = Float8(wr, i, 3);
    if (!PQgetisnull(wr, i, 4)) {
      w.checkpoint_index = static_cast<uint64_t>(Int8(wr, i, 4));
      w.checkpoint_tick = Int8(wr, i, 5);
      w.checkpoint = Bytes(wr, i, 6);
    }
    w.clock_s = clock_s;
    // Both lists are in bytewise world_id order (COLLATE "C").
    while (j < n_entries && Bytes(er, j, 0) < w.world_id) ++j;
    for (; j < n_entries && Bytes(er, j, 0) == w.world_id; ++j) {
      w.entries.push_back(JournalEntry{.world_id = w.world_id,
                                       .kind = w.kind,
                                       .index = static_cast<uint64_t>(Int8(er, j, 1)),
                                       .tick = Int8(er, j, 2),
                                       .seat = Int4(er, j, 3),
                                       .type = static_cast<uint32_t>(Int8(er, j, 4)),
                                       .body = Bytes(er, j, 5),
                                       .anchor_s = Float8(er, j, 6)});
    }
    out->push_back(std::move(w));
  }
  return absl::OkStatus();
}

absl::StatusOr<std::vector<StoredWorld>> PostgresStore::Load() {
  std::vector<StoredWorld> worlds;
  absl::Status status = writer_->Run([&]() -> absl::Status {
    if (absl::Status s = Fatal(); !s.ok()) return s;
    if (absl::Status s = Connected(/*probe=*/true); !s.ok()) return Failed("load", s);
    // One snapshot for both queries.
    absl::StatusOr<Result> r =
        Exec("BEGIN ISOLATION LEVEL REPEATABLE READ READ ONLY", {});
    if (!r.ok()) return Failed("load", r.status());
    absl::Status loaded = LoadOwner(options_.node, clock0_s_, &worlds);
    Rollback();
    return loaded.ok() ? loaded : Failed("load", loaded);
  });
  if (!status.ok()) return status;
  return worlds;
}

absl::StatusOr<std::vector<StoredWorld>> PostgresStore::Adopt() {
  std::vector<StoredWorld> adopted;
  absl::Status status = writer_->Run([&]() -> absl::Status {
    if (absl::Status s = Fatal(); !s.ok()) return s;
    if (absl::Status s = Connected(/*probe=*/true); !s.ok()) return Failed("adopt", s);
    auto fail = [&](const absl::Status& why) {
      Rollback();
      adopted.clear();
      return Fatal().ok() ? Failed("adopt", why) : Fatal();
    };
    absl::StatusOr<Result> r = Exec("BEGIN", {});
    if (!r.ok()) return fail(r.status());
    if (absl::Status s = CheckLease(); !s.ok()) return fail(s);
    // Every other node that holds worlds and whose lease lapsed, by the database's clock;
    // locked, so that two nodes adopting at once do not both take the same worlds.
    absl::StatusOr<Result> lapsed = Exec(
        "SELECT n.name, n.clock_s FROM journal_nodes n WHERE n.name <> $1 "
        "AND n.expires_at <= now() "
        "AND EXISTS (SELECT 1 FROM journal_worlds w WHERE w.owner = n.name) "
        "ORDER BY n.name FOR UPDATE OF n",
        {options_.node});
    if (!lapsed.ok()) return fail(lapsed.status());
    for (int i = 0; i < PQntuples(lapsed->get()); ++i) {
      const std::string node = Bytes(lapsed->get(), i, 0);
      const double clock_s = Float8(lapsed->get(), i, 1);
      // Fenced: whatever that node still tries to write fails its lease check.
      r = Exec("UPDATE journal_nodes SET epoch = epoch + 1 WHERE name = $1", {node});
      if (!r.ok()) return fail(r.status());
      if (absl::Status s = LoadOwner(node, clock_s, &adopted); !s.ok()) return fail(s);
      r = Exec("UPDATE journal_worlds SET owner = $1 WHERE owner = $2", {options_.node, node});
      if (!r.ok()) return fail(r.status());
    }
    r = Exec("COMMIT", {});
    if (!r.ok()) return fail(r.status());
    if (std::string_view(PQcmdStatus(r->get())) != "COMMIT") {
      return fail(absl::AbortedError("the transaction was rolled back"));
    }
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return adopted;
}

}  // namespace

absl::StatusOr<std::unique_ptr<Store>> OpenPostgres(const StoreOptions& options) {
  return PostgresStore::Open(options);
}

}  // namespace sportsim::server::store
