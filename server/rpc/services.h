// The gRPC services: thin translation from proto to sim calls and back.
#ifndef SPORTSIM_SERVER_SERVICES_H_
#define SPORTSIM_SERVER_SERVICES_H_

#include <memory>

#include <grpcpp/impl/codegen/service_type.h>

#include "sportsim/v1/common.pb.h"

namespace sportsim::server {

class SessionRegistry;
class TableRegistry;

/// The capabilities this build serves (also used by tests).
v1::GetInfoResponse MakeServerInfo();

std::unique_ptr<grpc::Service> MakeInfoService();
/// Swing: SimulateSwing, SimulateFlight and the sessions of `sessions` (which must outlive it).
std::unique_ptr<grpc::Service> MakeSwingService(SessionRegistry* sessions);
/// Billiards: SimulateShot and the tables of `tables` (which must outlive the service).
std::unique_ptr<grpc::Service> MakeBilliardsService(TableRegistry* tables);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_SERVICES_H_
