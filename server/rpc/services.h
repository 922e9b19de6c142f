// The gRPC services: thin translation from proto to sim calls and back.
#ifndef SPORTSIM_SERVER_RPC_SERVICES_H_
#define SPORTSIM_SERVER_RPC_SERVICES_H_

#include <cstdint>
#include <memory>

#include <grpcpp/impl/codegen/service_type.h>

#include "absl/time/time.h"
#include "sportsim/v1/common.pb.h"

namespace sportsim::server {

class SessionRegistry;
class RoundRegistry;
class TableRegistry;
class WorkPool;

/// Per-call bounds of server streams that compute ahead of their reader (SimulateShots).
struct StreamLimits {
  int64_t window_bytes = 1 << 20;  ///< finished, unsent work per call (--stream_window_bytes)
  /// A write that makes no progress this long ends the call, as does an upload that receives
  /// nothing this long (--stream_stall_timeout; 0: never).
  absl::Duration stall_timeout = absl::Seconds(30);
  /// What UploadCalibration's uploads in progress may hold in all (--max_upload_bytes).
  int64_t upload_bytes = int64_t{64} << 20;
};

/// The capabilities this build serves (also used by tests).
v1::GetInfoResponse MakeServerInfo();

std::unique_ptr<grpc::Service> MakeInfoService();
/// Swing: SimulateSwing, SimulateFlight and the sessions of `sessions`. Simulations (and
/// StartSwing, whose dry run is one) run on `pool`. Both must outlive the service.
std::unique_ptr<grpc::Service> MakeSwingService(SessionRegistry* sessions, RoundRegistry* rounds,
                                                WorkPool* pool);
/// Billiards: SimulateShot (on `pool`) and the tables of `tables`. Both must outlive it.
std::unique_ptr<grpc::Service> MakeBilliardsService(TableRegistry* tables, WorkPool* pool,
                                                    int64_t max_reply_bytes,
                                                    double cpu_budget_s,
                                                    StreamLimits streams = {});

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_RPC_SERVICES_H_
