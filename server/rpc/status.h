// absl::Status <-> grpc::Status: the one table that maps our codes to gRPC's.
#ifndef SPORTSIM_SERVER_RPC_STATUS_H_
#define SPORTSIM_SERVER_RPC_STATUS_H_

#include <grpcpp/support/status.h>

#include <string_view>

#include "absl/status/status.h"

namespace sportsim::server {

grpc::StatusCode ToGrpcCode(absl::StatusCode code);
grpc::Status ToGrpcStatus(const absl::Status& status);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_RPC_STATUS_H_
