// absl::Status <-> grpc::Status: the one table that maps our codes to gRPC's.
#ifndef SPORTSIM_SERVER_RPC_STATUS_H_
#define SPORTSIM_SERVER_RPC_STATUS_H_

#include <grpcpp/support/status.h>

#include <string>
#include <string_view>

#include "absl/status/status.h"

namespace sportsim::server {

grpc::StatusCode ToGrpcCode(absl::StatusCode code);
/// Every status a client sees: the code mapped, and the message bounded (at most
/// kMaxStatusMessageBytes, printable ASCII; anything else becomes '?'), so that no request can
/// make an error message carry its own bulk back, or past the client's metadata limit.
grpc::Status ToGrpcStatus(const absl::Status& status);

inline constexpr size_t kMaxStatusMessageBytes = 512;
/// The message as ToGrpcStatus sends it.
std::string BoundedMessage(std::string_view message);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_RPC_STATUS_H_
