#include "tests/support/postgres_cluster.h"

#include <fcntl.h>
#include <netinet/in.h>
#include <pwd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"

namespace sportsim::testing {
namespace {

/// A free TCP port on 127.0.0.1 (bound to port 0 and read back; the window until the server
/// binds it is short).
absl::StatusOr<int> FreePort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return absl::InternalError(absl::StrCat("socket: ", std::strerror(errno)));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  socklen_t len = sizeof addr;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    const int err = errno;
    ::close(fd);
    return absl::InternalError(absl::StrCat("binding a loopback port: ", std::strerror(err)));
  }
  ::close(fd);
  return ntohs(addr.sin_port);
}

/// The last `max` bytes of a file.
std::string Tail(const std::string& path, size_t max = 2000) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  return s.size() > max ? "..." + s.substr(s.size() - max) : s;
}

}  // namespace

absl::StatusOr<std::unique_ptr<PostgresCluster>> PostgresCluster::Create() {
  const std::string bin = kBinDir;
  if (::access((bin + "/initdb").c_str(), X_OK) != 0) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "%s/initdb not found: PostgreSQL 15 is not installed (scripts/setup installs "
        "postgresql-15)",
        bin));
  }
  std::unique_ptr<PostgresCluster> c(new PostgresCluster());
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern = absl::StrCat(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp",
                                     "/sportsim-pg-XXXXXX");
  if (::mkdtemp(pattern.data()) == nullptr) {
    return absl::FailedPreconditionError(
        absl::StrFormat("mkdtemp %s: %s", pattern, std::strerror(errno)));
  }
  c->dir_ = pattern;
  c->data_ = c->dir_ + "/data";
  // The server's user must reach its data directory through ours.
  if (::chmod(c->dir_.c_str(), 0755) != 0 || ::mkdir(c->data_.c_str(), 0700) != 0) {
    return absl::FailedPreconditionError(
        absl::StrFormat("preparing %s: %s", c->data_, std::strerror(errno)));
  }
  if (::geteuid() == 0) {
    const passwd* nobody = ::getpwnam("nobody");
    if (nobody == nullptr) return absl::FailedPreconditionError("no user nobody to run PostgreSQL");
    if (::chown(c->data_.c_str(), nobody->pw_uid, nobody->pw_gid) != 0) {
      return absl::FailedPreconditionError(
          absl::StrFormat("chown nobody %s: %s", c->data_, std::strerror(errno)));
    }
  }
  absl::StatusOr<int> port = FreePort();
  if (!port.ok()) return port.status();
  c->port_ = *port;
  // -N: no fsync while initializing (a throwaway cluster); the server itself fsyncs as usual.
  if (absl::Status s = c->Run({bin + "/initdb", "-D", c->data_, "-U", "sportsim",
                               "--auth=trust", "-N", "-E", "UTF8", "--locale=C"},
                              /*as_server=*/true);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = c->Start(); !s.ok()) return s;
  if (absl::Status s =
          c->Run({bin + "/createdb", "-h", "127.0.0.1", "-p", absl::StrCat(c->port_), "-U",
                  "sportsim", "sportsim"},
                 /*as_server=*/false);
      !s.ok()) {
    return s;
  }
  return c;
}

absl::StatusOr<PostgresCluster*> PostgresCluster::Shared() {
  // Made once (thread-safe static initialization); stopped and removed at exit.
  static absl::StatusOr<std::unique_ptr<PostgresCluster>>* const shared = [] {
    auto* made = new absl::StatusOr<std::unique_ptr<PostgresCluster>>(Create());
    std::atexit([] {
      if (shared->ok()) shared->value().reset();
    });
    return made;
  }();
  if (!shared->ok()) return shared->status();
  return shared->value().get();
}

PostgresCluster::~PostgresCluster() {
  if (running_) Stop().IgnoreError();
  if (!dir_.empty()) {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
}

std::string PostgresCluster::UriOf(const std::string& database) const {
  return absl::StrFormat("postgresql://sportsim@127.0.0.1:%d/%s", port_, database);
}

absl::StatusOr<std::string> PostgresCluster::NewDatabase(std::string name) {
  if (name.empty()) name = absl::StrCat("t", ++databases_);
  if (absl::Status s = Run({std::string(kBinDir) + "/createdb", "-h", "127.0.0.1", "-p",
                            absl::StrCat(port_), "-U", "sportsim", name},
                           /*as_server=*/false);
      !s.ok()) {
    return s;
  }
  return UriOf(name);
}

absl::Status PostgresCluster::Stop() {
  absl::Status s = Run({std::string(kBinDir) + "/pg_ctl", "-D", data_, "-m", "immediate", "-w",
                        "stop"},
                       /*as_server=*/true);
  if (s.ok()) running_ = false;
  return s;
}

absl::Status PostgresCluster::Start() {
  const std::string server_options = absl::StrFormat(
      "-p %d -k %s -c listen_addresses=127.0.0.1", port_, data_);
  absl::Status s = Run({std::string(kBinDir) + "/pg_ctl", "-D", data_, "-o", server_options,
                        "-l", data_ + "/log", "-w", "-t", "60", "start"},
                       /*as_server=*/true);
  if (!s.ok()) {
    return absl::FailedPreconditionError(
        absl::StrCat(s.message(), "\nserver log:\n", Tail(data_ + "/log")));
  }
  running_ = true;
  return absl::OkStatus();
}

absl::Status PostgresCluster::Run(const std::vector<std::string>& argv, bool as_server) {
  std::vector<std::string> args;
  if (as_server && ::geteuid() == 0) args = {"/usr/sbin/runuser", "-u", "nobody", "--"};
  args.insert(args.end(), argv.begin(), argv.end());
  const std::string log = dir_ + "/commands.log";
  const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (out < 0) {
    return absl::FailedPreconditionError(
        absl::StrFormat("opening %s: %s", log, std::strerror(errno)));
  }
  std::vector<char*> cargv;
  for (std::string& a : args) cargv.push_back(a.data());
  cargv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    // The child: output to the log (a file, not a pipe: pg_ctl's postmaster keeps it open),
    // in a directory the server's user can enter.
    ::dup2(out, 1);
    ::dup2(out, 2);
    const int null = ::open("/dev/null", O_RDONLY);
    if (null >= 0) ::dup2(null, 0);
    if (::chdir(dir_.c_str()) != 0) _exit(126);
    ::execv(cargv[0], cargv.data());
    _exit(127);
  }
  ::close(out);
  if (pid < 0) return absl::InternalError(absl::StrCat("fork: ", std::strerror(errno)));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    return absl::FailedPreconditionError(
        absl::StrFormat("PostgreSQL test cluster: `%s` failed (status %d):\n%s",
                        absl::StrJoin(argv, " "), status, Tail(log)));
  }
  return absl::OkStatus();
}

}  // namespace sportsim::testing
