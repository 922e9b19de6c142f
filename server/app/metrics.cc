#include "server/app/metrics.h"

#include "server/app/server_app.h"
#include "server/world/work_pool.h"

#include <grpcpp/grpcpp.h>
#include <grpcpp/support/server_interceptor.h>
#include <prometheus/collectable.h>
#include <prometheus/exposer.h>
#include <prometheus/metric_family.h>

#include <exception>
#include <map>
#include <tuple>
#include <vector>

#include "absl/strings/str_format.h"
#include "server/world/scheduler.h"
#include "server/swing/session_world.h"
#include "server/billiards/table_world.h"
#include "server/store/store.h"
#include "server/world/world.h"

namespace sportsim::server {

// ---------------------------------------------------------------------------------------------
// RPC counting

void RpcCounters::Count(const std::string& method, int code) {
  absl::MutexLock lock(&mu_);
  ++counts_[{method, code}];
}

std::map<std::pair<std::string, int>, int64_t> RpcCounters::Snapshot() const {
  absl::MutexLock lock(&mu_);
  return counts_;
}

namespace {

class CountingInterceptor final : public grpc::experimental::Interceptor {
 public:
  CountingInterceptor(RpcCounters* counters, const char* method)
      : counters_(counters), method_(method != nullptr ? method : "unknown") {
    counters_->Begin();
  }
  ~CountingInterceptor() override { counters_->End(); }
  CountingInterceptor(const CountingInterceptor&) = delete;
  CountingInterceptor& operator=(const CountingInterceptor&) = delete;
  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(
            grpc::experimental::InterceptionHookPoints::PRE_SEND_STATUS)) {
      counters_->Count(method_, static_cast<int>(methods->GetSendStatus().error_code()));
    }
    methods->Proceed();
  }

 private:
  RpcCounters* const counters_;
  const std::string method_;
};

class CountingFactory final : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  explicit CountingFactory(RpcCounters* counters) : counters_(counters) {}
  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo* info) override {
    return new CountingInterceptor(counters_, info->method());
  }

 private:
  RpcCounters* const counters_;
};

const char* CodeName(int code) {
  static constexpr const char* kNames[] = {
      "OK",        "CANCELLED",          "UNKNOWN",        "INVALID_ARGUMENT",
      "DEADLINE_EXCEEDED", "NOT_FOUND",  "ALREADY_EXISTS", "PERMISSION_DENIED",
      "RESOURCE_EXHAUSTED", "FAILED_PRECONDITION", "ABORTED", "OUT_OF_RANGE",
      "UNIMPLEMENTED", "INTERNAL", "UNAVAILABLE", "DATA_LOSS", "UNAUTHENTICATED"};
  return code >= 0 && code <= 16 ? kNames[code] : "UNKNOWN";
}

// Codes that mean the caller's input was refused (not a server fault, not a cancellation).
bool IsRejection(int code) {
  switch (static_cast<grpc::StatusCode>(code)) {
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::NOT_FOUND:
    case grpc::StatusCode::PERMISSION_DENIED:
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
    case grpc::StatusCode::FAILED_PRECONDITION:
    case grpc::StatusCode::OUT_OF_RANGE:
    case grpc::StatusCode::UNAUTHENTICATED:
      return true;
    default:
      return false;
  }
}

using prometheus::ClientMetric;
using prometheus::MetricFamily;
using prometheus::MetricType;

MetricFamily Family(std::string name, std::string help, MetricType type) {
  MetricFamily f;
  f.name = std::move(name);
  f.help = std::move(help);
  f.type = type;
  return f;
}

void Add(MetricFamily* f, double value, std::vector<ClientMetric::Label> labels = {}) {
  ClientMetric m;
  m.label = std::move(labels);
  if (f->type == MetricType::Counter) {
    m.counter.value = value;
  } else {
    m.gauge.value = value;
  }
  f->metric.push_back(std::move(m));
}

// A LatencyHistogram as a Prometheus histogram, with one bucket per power of two of
// microseconds (every fourth of its 128 buckets), 1 us to about 1 h.
void AddHistogram(MetricFamily* f, const LatencyHistogram& h,
                  std::vector<ClientMetric::Label> labels = {}) {
  ClientMetric m;
  m.label = std::move(labels);
  const std::vector<int64_t> counts = h.Counts();
  uint64_t cumulative = 0;
  for (int i = 0; i < LatencyHistogram::kBuckets; ++i) {
    cumulative += static_cast<uint64_t>(counts[static_cast<size_t>(i)]);
    if (i % 4 == 3 && i < 4 * 32) {
      m.histogram.bucket.push_back({cumulative, LatencyHistogram::UpperEdge(i)});
    }
  }
  m.histogram.bucket.push_back({cumulative, std::numeric_limits<double>::infinity()});
  m.histogram.sample_count = cumulative;
  m.histogram.sample_sum = h.Sum();
  f->metric.push_back(std::move(m));
}

class Collector final : public prometheus::Collectable {
 public:
  Collector(TableRegistry* tables, SessionRegistry* sessions, TickScheduler* scheduler,
            WorkPool* pool, RpcCounters* rpcs, store::Store* journal)
      : tables_(tables),
        sessions_(sessions),
        scheduler_(scheduler),
        pool_(pool),
        rpcs_(rpcs),
        journal_(journal) {}

  std::vector<MetricFamily> Collect() const override {
    // One row per kind of world: a new kind is one more entry here.
    struct Kind {
      const char* name;
      WorldStats stats;
      const LatencyHistogram* publish_to_write;
    };
    const SessionStats sessions = sessions_->stats();
    const Kind kinds[] = {{"table", tables_->stats(), &tables_->publish_to_write()},
                          {"session", sessions, &sessions_->publish_to_write()}};
    std::vector<MetricFamily> out;
    const auto per_world = [&](const char* name, const char* help, MetricType type,
                               auto value) {
      MetricFamily f = Family(name, help, type);
      for (const Kind& k : kinds) {
        Add(&f, static_cast<double>(value(k.stats)), {{"world", k.name}});
      }
      out.push_back(std::move(f));
    };
    {
      MetricFamily f = Family("sportsim_tick_duration_seconds",
                              "Wall time of one wake of one world on a tick worker (a tick, "
                              "catch-up ticks, or a heartbeat)",
                              MetricType::Histogram);
      AddHistogram(&f, scheduler_->wake_durations());
      out.push_back(std::move(f));
    }
    {
      MetricFamily f = Family("sportsim_tick_worker_cpu_seconds_total",
                              "Thread CPU time the tick workers spent", MetricType::Counter);
      Add(&f, static_cast<double>(scheduler_->cpu_ns()) * 1e-9);
      out.push_back(std::move(f));
    }
    per_world("sportsim_ticks_total", "World ticks advanced", MetricType::Counter,
              [](const WorldStats& s) { return s.ticks; });
    per_world("sportsim_late_ticks_total",
              "Ticks advanced more than one period after their deadline", MetricType::Counter,
              [](const WorldStats& s) { return s.late_ticks; });
    per_world("sportsim_slipped_ticks_total",
              "Ticks skipped by slipping a world's clock (too far behind to catch up)",
              MetricType::Counter, [](const WorldStats& s) { return s.slipped_ticks; });
    per_world("sportsim_worlds", "Tables and swing sessions held", MetricType::Gauge,
              [](const WorldStats& s) { return s.worlds; });
    per_world("sportsim_worlds_active", "Tables with moving balls, sessions mid-swing",
              MetricType::Gauge, [](const WorldStats& s) { return s.running; });
    per_world("sportsim_watchers", "Open snapshot streams (WatchTable, WatchSwing, DriveSwing)",
              MetricType::Gauge, [](const WorldStats& s) { return s.watchers; });
    per_world("sportsim_snapshots_sent_total", "Snapshots written to streams",
              MetricType::Counter, [](const WorldStats& s) { return s.snapshots_sent; });
    per_world("sportsim_snapshots_replaced_total",
              "Snapshots overtaken by a newer one before a slow reader took them (latest wins)",
              MetricType::Counter, [](const WorldStats& s) { return s.snapshots_replaced; });
    per_world("sportsim_resyncs_total",
              "Readers that fell more than --watcher_backlog events behind (sent the full state)",
              MetricType::Counter, [](const WorldStats& s) { return s.resyncs; });
    per_world("sportsim_events_total", "World events queued to readers (shots, collisions, "
              "impacts, torques...)",
              MetricType::Counter, [](const WorldStats& s) { return s.events; });
    {
      MetricFamily f = Family("sportsim_publish_to_write_seconds",
                              "From a tick's deadline to the start of its snapshot's write",
                              MetricType::Histogram);
      for (const Kind& k : kinds) AddHistogram(&f, *k.publish_to_write, {{"world", k.name}});
      out.push_back(std::move(f));
    }
    {
      MetricFamily f = Family("sportsim_swing_commands_total",
                              "DriveSwing torque commands applied", MetricType::Counter);
      Add(&f, static_cast<double>(sessions.commands));
      out.push_back(std::move(f));
    }
    {
      MetricFamily f = Family("sportsim_malformed_messages_total",
                              "Malformed request messages libprotobuf reported (e.g. invalid "
                              "UTF-8 in a string field), counted instead of logged",
                              MetricType::Counter);
      Add(&f, static_cast<double>(ProtobufLogMessages()));
      out.push_back(std::move(f));
    }
    {
      MetricFamily f = Family("sportsim_simulations_queued",
                              "Simulations waiting for a worker of the simulation pool",
                              MetricType::Gauge);
      Add(&f, pool_->queued());
      out.push_back(std::move(f));
    }
    {
      MetricFamily f = Family("sportsim_simulations_running",
                              "Simulations running on the simulation pool", MetricType::Gauge);
      Add(&f, pool_->running());
      out.push_back(std::move(f));
    }
    {
      MetricFamily f = Family("sportsim_simulations_refused_total",
                              "Simulations refused because the queue was full",
                              MetricType::Counter);
      Add(&f, static_cast<double>(pool_->refused()));
      out.push_back(std::move(f));
    }
    {
      MetricFamily f = Family("sportsim_simulations_over_budget_total",
                              "Simulations stopped by their CPU budget (--max_request_cpu)",
                              MetricType::Counter);
      Add(&f, static_cast<double>(pool_->budget_exhausted()));
      out.push_back(std::move(f));
    }
    if (journal_ != nullptr) {
      const store::StoreStats j = journal_->stats();
      for (const auto& [name, help, value] :
           {std::tuple{"sportsim_journal_commits_total",
                       "Journal write transactions committed (each one sync to disk)",
                       j.batches},
            std::tuple{"sportsim_journal_writes_total",
                       "Journal writes in committed batches, refused ones included (commands, "
                       "creations, deletions, checkpoints)",
                       j.ops},
            std::tuple{"sportsim_journal_failed_commits_total",
                       "Journal write transactions that failed (their commands were refused)",
                       j.failed_batches}}) {
        MetricFamily f = Family(name, help, MetricType::Counter);
        Add(&f, static_cast<double>(value));
        out.push_back(std::move(f));
      }
      MetricFamily up = Family("sportsim_journal_up",
                               "1 while commands can be made durable, else 0", MetricType::Gauge);
      Add(&up, journal_->Healthy().ok() ? 1.0 : 0.0);
      out.push_back(std::move(up));
    }
    // Rejected inputs: RPCs ending with a caller-error code, and refused DriveSwing commands.
    std::map<int, int64_t> rejected;
    MetricFamily rpcs = Family("sportsim_rpcs_total", "RPCs finished, by method and status code",
                               MetricType::Counter);
    for (const auto& [key, n] : rpcs_->Snapshot()) {
      Add(&rpcs, static_cast<double>(n), {{"method", key.first}, {"code", CodeName(key.second)}});
      if (IsRejection(key.second)) rejected[key.second] += n;
    }
    for (int c = 0; c < 17; ++c) {
      if (sessions.refused_by_code[static_cast<size_t>(c)] > 0) {
        rejected[c] += sessions.refused_by_code[static_cast<size_t>(c)];
      }
    }
    out.push_back(std::move(rpcs));
    MetricFamily rej = Family("sportsim_rejected_inputs_total",
                              "Requests and stream commands refused, by status code (bad input, "
                              "unknown ids, wrong tokens, limits, late commands)",
                              MetricType::Counter);
    for (const auto& [code, n] : rejected) {
      Add(&rej, static_cast<double>(n), {{"code", CodeName(code)}});
    }
    out.push_back(std::move(rej));
    return out;
  }

 private:
  TableRegistry* const tables_;
  SessionRegistry* const sessions_;
  TickScheduler* const scheduler_;
  WorkPool* const pool_;
  RpcCounters* const rpcs_;
  store::Store* const journal_;  // null: no journal
};

}  // namespace

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> MakeRpcCountingInterceptor(
    RpcCounters* counters) {
  return std::make_unique<CountingFactory>(counters);
}

absl::StatusOr<std::unique_ptr<MetricsEndpoint>> MetricsEndpoint::Start(
    const std::string& listen, TableRegistry* tables, SessionRegistry* sessions,
    TickScheduler* scheduler, WorkPool* pool, RpcCounters* rpcs, store::Store* journal) {
  std::unique_ptr<MetricsEndpoint> e(new MetricsEndpoint());
  auto collector = std::make_shared<Collector>(tables, sessions, scheduler, pool, rpcs, journal);
  try {
    // One civetweb thread: a scrape every few seconds needs no more.
    e->exposer_ = std::make_unique<prometheus::Exposer>(listen, /*num_threads=*/1);
  } catch (const std::exception& ex) {
    return absl::UnavailableError(
        absl::StrFormat("--metrics_listen: cannot listen on %s: %s", listen, ex.what()));
  }
  e->exposer_->RegisterCollectable(collector);
  const std::vector<int> ports = e->exposer_->GetListeningPorts();
  e->port_ = ports.empty() ? 0 : ports.front();
  e->collectable_ = collector;
  return e;
}

MetricsEndpoint::~MetricsEndpoint() = default;

}  // namespace sportsim::server
