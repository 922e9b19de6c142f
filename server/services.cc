#include "server/services.h"

#include <google/protobuf/stubs/common.h>
#include <grpcpp/grpcpp.h>

#include "server/billiards_convert.h"
#include "server/status_util.h"
#include "server/tables.h"
#include "sim/billiards/shot.h"
#include "sim/core/cpu_clock.h"
#include "server/swing_convert.h"
#include "sim/swing/swing_simulation.h"
#include "sportsim/v1/billiards.grpc.pb.h"
#include "sportsim/v1/common.grpc.pb.h"
#include "sportsim/v1/swing.grpc.pb.h"

#ifndef SPORTSIM_VERSION
#define SPORTSIM_VERSION "unknown"
#endif
#ifndef SPORTSIM_BUILD_TYPE
#define SPORTSIM_BUILD_TYPE "unknown"
#endif
#ifndef SPORTSIM_COMPILER
#define SPORTSIM_COMPILER "unknown"
#endif

namespace sportsim::server {
namespace {

class InfoService final : public v1::Server::CallbackService {
  grpc::ServerUnaryReactor* GetInfo(grpc::CallbackServerContext* ctx, const v1::GetInfoRequest*,
                                    v1::GetInfoResponse* response) override {
    *response = MakeServerInfo();
    auto* reactor = ctx->DefaultReactor();
    reactor->Finish(grpc::Status::OK);
    return reactor;
  }
};

class SwingService final : public v1::Swing::CallbackService {
  grpc::ServerUnaryReactor* SimulateSwing(grpc::CallbackServerContext* ctx,
                                          const v1::SimulateSwingRequest* request,
                                          v1::SimulateSwingResponse* response) override {
    auto* reactor = ctx->DefaultReactor();
    reactor->Finish(ToGrpcStatus(Simulate(*request, response, ctx)));
    return reactor;
  }

  // A deadline, a client that goes away or a server shutdown past its grace cancels the call;
  // the run polls that and stops.
  static absl::Status Simulate(const v1::SimulateSwingRequest& request,
                               v1::SimulateSwingResponse* response,
                               grpc::CallbackServerContext* ctx) {
    absl::StatusOr<SwingJob> job = SwingJobFromProto(request);
    if (!job.ok()) return job.status();
    job->run.cancelled = [ctx] { return ctx->IsCancelled(); };
    const double cpu0 = ThreadCpuSeconds();
    absl::StatusOr<swing::SwingRunResult> result =
        swing::SimulateSwing(job->model, job->program, job->solver, job->run);
    const double cpu_s = ThreadCpuSeconds() - cpu0;
    if (!result.ok()) return result.status();
    SwingResultToProto(*result, cpu_s, response);
    return absl::OkStatus();
  }

  grpc::ServerUnaryReactor* SimulateFlight(grpc::CallbackServerContext* ctx,
                                           const v1::SimulateFlightRequest* request,
                                           v1::SimulateFlightResponse* response) override {
    auto* reactor = ctx->DefaultReactor();
    reactor->Finish(ToGrpcStatus(Fly(*request, response)));
    return reactor;
  }

  static absl::Status Fly(const v1::SimulateFlightRequest& request,
                          v1::SimulateFlightResponse* response) {
    absl::StatusOr<FlightJob> job = FlightJobFromProto(request);
    if (!job.ok()) return job.status();
    const double cpu0 = ThreadCpuSeconds();
    absl::StatusOr<swing::FlightResult> result =
        swing::SimulateFlight(job->ball, job->launch, job->atmosphere, job->wind, job->options);
    const double cpu_s = ThreadCpuSeconds() - cpu0;
    if (!result.ok()) return result.status();
    FlightResultToProto(*result, cpu_s, response);
    return absl::OkStatus();
  }
};

// One WatchTable stream: the registry's Watcher decides what to write and when; this reactor
// only carries it to gRPC and back.
class WatchReactor final : public grpc::ServerWriteReactor<v1::TableSnapshot>,
                           public SnapshotSink {
 public:
  WatchReactor(TableRegistry* registry, const v1::WatchTableRequest& request)
      : registry_(registry), table_id_(request.table_id()) {
    absl::StatusOr<std::shared_ptr<Watcher>> watcher = registry->Watch(request, this);
    if (!watcher.ok()) {
      Finish(ToGrpcStatus(watcher.status()));
      return;
    }
    watcher_ = *std::move(watcher);
    watcher_->Pump();
  }

  void SinkWrite(const v1::TableSnapshot* snapshot) override { StartWrite(snapshot); }
  void SinkWriteLast(const v1::TableSnapshot* snapshot, const absl::Status& status) override {
    StartWriteAndFinish(snapshot, grpc::WriteOptions(), ToGrpcStatus(status));
  }
  void SinkFinish(const absl::Status& status) override { Finish(ToGrpcStatus(status)); }

  void OnWriteDone(bool ok) override { watcher_->OnWriteDone(ok); }
  void OnCancel() override {
    if (watcher_ != nullptr) watcher_->OnCancel();
  }
  void OnDone() override {
    if (watcher_ != nullptr) {
      watcher_->OnDone();
      registry_->Unwatch(table_id_, watcher_.get());
    }
    delete this;
  }

 private:
  TableRegistry* const registry_;
  const std::string table_id_;
  std::shared_ptr<Watcher> watcher_;
};

// Unary calls on the registry: the status, or the response.
template <typename Response, typename Fn>
grpc::ServerUnaryReactor* Unary(grpc::CallbackServerContext* ctx, Response* response, Fn fn) {
  auto* reactor = ctx->DefaultReactor();
  absl::StatusOr<Response> result = fn();
  if (result.ok()) *response = *std::move(result);
  reactor->Finish(ToGrpcStatus(result.status()));
  return reactor;
}

class BilliardsService final : public v1::Billiards::CallbackService {
 public:
  explicit BilliardsService(TableRegistry* tables) : tables_(tables) {}

 private:
  TableRegistry* const tables_;

  grpc::ServerUnaryReactor* CreateTable(grpc::CallbackServerContext* ctx,
                                        const v1::CreateTableRequest* request,
                                        v1::CreateTableResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->Create(*request); });
  }
  grpc::ServerUnaryReactor* GetTable(grpc::CallbackServerContext* ctx,
                                     const v1::GetTableRequest* request,
                                     v1::TableInfo* response) override {
    return Unary(ctx, response, [&] { return tables_->Get(*request); });
  }
  grpc::ServerUnaryReactor* ListTables(grpc::CallbackServerContext* ctx,
                                       const v1::ListTablesRequest* request,
                                       v1::ListTablesResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->List(*request); });
  }
  grpc::ServerUnaryReactor* DeleteTable(grpc::CallbackServerContext* ctx,
                                        const v1::DeleteTableRequest* request,
                                        v1::DeleteTableResponse* response) override {
    return Unary(ctx, response, [&]() -> absl::StatusOr<v1::DeleteTableResponse> {
      if (absl::Status s = tables_->Delete(*request); !s.ok()) return s;
      return v1::DeleteTableResponse();
    });
  }
  grpc::ServerUnaryReactor* ResetTable(grpc::CallbackServerContext* ctx,
                                       const v1::ResetTableRequest* request,
                                       v1::ResetTableResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->Reset(*request); });
  }
  grpc::ServerUnaryReactor* PlaceBall(grpc::CallbackServerContext* ctx,
                                      const v1::PlaceBallRequest* request,
                                      v1::PlaceBallResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->Place(*request); });
  }
  grpc::ServerUnaryReactor* Shoot(grpc::CallbackServerContext* ctx,
                                  const v1::ShootRequest* request,
                                  v1::ShootResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->Shoot(*request); });
  }
  grpc::ServerUnaryReactor* SetTurn(grpc::CallbackServerContext* ctx,
                                    const v1::SetTurnRequest* request,
                                    v1::SetTurnResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->SetTurn(*request); });
  }
  grpc::ServerWriteReactor<v1::TableSnapshot>* WatchTable(
      grpc::CallbackServerContext*, const v1::WatchTableRequest* request) override {
    return new WatchReactor(tables_, *request);
  }

  grpc::ServerUnaryReactor* SimulateShot(grpc::CallbackServerContext* ctx,
                                         const v1::SimulateShotRequest* request,
                                         v1::SimulateShotResponse* response) override {
    auto* reactor = ctx->DefaultReactor();
    reactor->Finish(ToGrpcStatus(Simulate(*request, response, ctx)));
    return reactor;
  }

  static absl::Status Simulate(const v1::SimulateShotRequest& request,
                               v1::SimulateShotResponse* response,
                               grpc::CallbackServerContext* ctx) {
    absl::StatusOr<ShotJob> job = ShotJobFromProto(request);
    if (!job.ok()) return job.status();
    job->shot.cancelled = [ctx] { return ctx->IsCancelled(); };
    absl::StatusOr<billiards::ShotResult> result = billiards::SimulateShot(
        job->table.model, job->solver, job->table.state, job->shot);
    if (!result.ok()) return result.status();
    ShotResultToProto(*job, *result, response);
    return absl::OkStatus();
  }
};

}  // namespace

v1::GetInfoResponse MakeServerInfo() {
  v1::GetInfoResponse info;
  info.set_version(SPORTSIM_VERSION);
  info.set_build_type(SPORTSIM_BUILD_TYPE);
  info.set_compiler(SPORTSIM_COMPILER);
  info.set_grpc_version(grpc::Version());
  info.set_protobuf_version(
      google::protobuf::internal::VersionString(GOOGLE_PROTOBUF_VERSION));
  v1::Capabilities* caps = info.mutable_capabilities();
  AddBilliardsCapabilities(caps);
  for (swing::SwingIntegrator i : swing::kAllSwingIntegrators) {
    caps->add_swing_integrators(std::string(swing::SwingIntegratorName(i)));
  }
  for (const std::string& e : SwingEffectNames()) caps->add_swing_effects(e);
  for (v1::ParameterInfo& p : SwingParameterInfo()) *caps->add_swing_parameters() = std::move(p);
  caps->add_services(v1::Server::service_full_name());
  caps->add_services(v1::Swing::service_full_name());
  caps->add_services(v1::Billiards::service_full_name());
  caps->add_services("grpc.health.v1.Health");
  caps->add_services("grpc.reflection.v1alpha.ServerReflection");
  return info;
}

std::unique_ptr<grpc::Service> MakeInfoService() { return std::make_unique<InfoService>(); }
std::unique_ptr<grpc::Service> MakeSwingService() { return std::make_unique<SwingService>(); }
std::unique_ptr<grpc::Service> MakeBilliardsService(TableRegistry* tables) {
  return std::make_unique<BilliardsService>(tables);
}

}  // namespace sportsim::server
