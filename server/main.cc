// sportsim-server: the authoritative sports-physics gRPC server.
#include <pthread.h>
#include <signal.h>

#include <cstdio>
#include <iostream>
#include <string>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_cat.h"
#include "absl/time/time.h"
#include "server/server_app.h"

ABSL_FLAG(std::string, listen, "127.0.0.1:50051",
          "Address to serve on, host:port or [ipv6]:port; port 0 picks a free port");
ABSL_FLAG(int, port, -1, "If set, overrides the port of --listen");
ABSL_FLAG(absl::Duration, shutdown_grace, absl::Seconds(5),
          "On SIGINT/SIGTERM, how long in-flight calls may take to finish before cancellation");

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "sportsim-server [--listen=HOST:PORT] [--port=N]: serves sportsim.v1 (Server, Swing), "
      "gRPC health and reflection. Stops cleanly on SIGINT or SIGTERM. --helpfull lists flags.");
  absl::ParseCommandLine(argc, argv);

  // Block the stop signals in every thread (gRPC's threads inherit this mask); main waits.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  sportsim::server::ServerConfig config;
  config.listen = absl::GetFlag(FLAGS_listen);
  if (const int port = absl::GetFlag(FLAGS_port); port >= 0) {
    absl::StatusOr<sportsim::server::ListenAddress> a =
        sportsim::server::ParseListenAddress(config.listen);
    if (!a.ok()) {
      std::cerr << "sportsim-server: " << a.status().message() << "\n";
      return 2;
    }
    const bool v6 = a->host.find(':') != std::string::npos;
    config.listen = v6 ? absl::StrCat("[", a->host, "]:", port) : absl::StrCat(a->host, ":", port);
  }
  absl::StatusOr<std::unique_ptr<sportsim::server::ServerApp>> app =
      sportsim::server::ServerApp::Start(config);
  if (!app.ok()) {
    std::cerr << "sportsim-server: " << app.status().message() << "\n";
    return 2;
  }
  std::cout << "sportsim-server listening on " << (*app)->address() << std::endl;

  int sig = 0;
  sigwait(&stop_signals, &sig);
  std::cout << "sportsim-server: " << (sig == SIGINT ? "SIGINT" : "SIGTERM")
            << ", draining" << std::endl;
  (*app)->Shutdown(absl::GetFlag(FLAGS_shutdown_grace));
  (*app)->Wait();
  std::cout << "sportsim-server: stopped" << std::endl;
  return 0;
}
