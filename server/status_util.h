// absl::Status <-> grpc::Status: the one table that maps our codes to gRPC's; and the prefix
// that names the request field a status concerns.
#ifndef SPORTSIM_SERVER_STATUS_UTIL_H_
#define SPORTSIM_SERVER_STATUS_UTIL_H_

#include <grpcpp/support/status.h>

#include <string_view>

#include "absl/status/status.h"

namespace sportsim::server {

grpc::StatusCode ToGrpcCode(absl::StatusCode code);
grpc::Status ToGrpcStatus(const absl::Status& status);

/// The same status with its message prefixed by the proto path it concerns ("table.rack: ",
/// "solver."); OK stays OK.
absl::Status PrefixStatus(std::string_view prefix, const absl::Status& s);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_STATUS_UTIL_H_
