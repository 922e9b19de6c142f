// A throwaway PostgreSQL 15 cluster for tests and benchmarks (Debian's postgresql-15): initdb in
// a temporary directory, a postmaster on a free loopback port, trust authentication for the
// user "sportsim", and a database "sportsim". PostgreSQL refuses to run as root, so as root the
// server's programs run as the user nobody (runuser); otherwise as the current user.
// Stop() and Start() stop it (immediately, as a crash would) and start it again on the same
// data and port, for tests of a database that goes away under a running server. The
// destructor stops it and removes its directory.
#ifndef SPORTSIM_TESTS_SUPPORT_POSTGRES_CLUSTER_H_
#define SPORTSIM_TESTS_SUPPORT_POSTGRES_CLUSTER_H_

#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace sportsim::testing {

class PostgresCluster {
 public:
  /// The server's programs (initdb, pg_ctl, createdb).
  static constexpr const char* kBinDir = "/usr/lib/postgresql/15/bin";

  /// Makes and starts a cluster: FAILED_PRECONDITION naming the step and its output when a
  /// step fails (PostgreSQL 15 not installed: scripts/setup installs it).
  static absl::StatusOr<std::unique_ptr<PostgresCluster>> Create();
  /// One cluster per process, made on first use (every test of a binary shares it; give each
  /// test its own database or node names). Never destroyed before exit.
  static absl::StatusOr<PostgresCluster*> Shared();

  ~PostgresCluster();  ///< stops the server and removes the directory
  PostgresCluster(const PostgresCluster&) = delete;
  PostgresCluster& operator=(const PostgresCluster&) = delete;

  /// "postgresql://sportsim@127.0.0.1:PORT/sportsim".
  std::string uri() const { return UriOf("sportsim"); }
  /// The URI of another database of this cluster.
  std::string UriOf(const std::string& database) const;
  /// Creates a fresh database ("t1", "t2", ... when `name` is empty) and returns its URI.
  absl::StatusOr<std::string> NewDatabase(std::string name = {});
  int port() const { return port_; }
  const std::string& dir() const { return dir_; }

  /// pg_ctl stop -m immediate: the server is gone at once, as if it crashed.
  absl::Status Stop();
  /// pg_ctl start on the same data directory and port; returns once it accepts connections.
  absl::Status Start();

 private:
  PostgresCluster() = default;
  /// Runs a program (as nobody when root and `as_server`), its output to DIR/commands.log;
  /// FAILED_PRECONDITION with the output's end when it fails.
  absl::Status Run(const std::vector<std::string>& argv, bool as_server);

  std::string dir_;   ///< the temporary directory (0755)
  std::string data_;  ///< dir_/data: the cluster, owned by the server's user
  int port_ = 0;
  bool running_ = false;
  int databases_ = 0;
};

}  // namespace sportsim::testing

#endif  // SPORTSIM_TESTS_SUPPORT_POSTGRES_CLUSTER_H_
