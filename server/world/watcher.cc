#include "server/world/watcher.h"

#include <algorithm>
#include <cmath>

namespace sportsim::server {

// ---------------------------------------------------------------------------------------------
// LatencyHistogram

void LatencyHistogram::Add(std::chrono::nanoseconds d) {
  const double us = std::max(1.0, static_cast<double>(d.count()) * 1e-3);
  const int i = std::clamp(static_cast<int>(4.0 * std::log2(us)), 0, kBuckets - 1);
  counts_[i].fetch_add(1, std::memory_order_relaxed);
  sum_ns_.fetch_add(d.count(), std::memory_order_relaxed);
}

std::vector<int64_t> LatencyHistogram::Counts() const {
  std::vector<int64_t> out(kBuckets);
  for (int i = 0; i < kBuckets; ++i) out[i] = counts_[i].load(std::memory_order_relaxed);
  return out;
}

double LatencyHistogram::Quantile(double q, const std::vector<int64_t>& since) const {
  std::vector<int64_t> c = Counts();
  if (!since.empty()) {
    for (int i = 0; i < kBuckets; ++i) c[i] -= since[i];
  }
  return QuantileOf(c, q);
}

double LatencyHistogram::QuantileOf(const std::vector<int64_t>& c, double q) {
  int64_t total = 0;
  for (int64_t n : c) total += n;
  if (total == 0) return 0.0;
  const double want = q * static_cast<double>(total);
  int64_t seen = 0;
  for (int i = 0; i < kBuckets; ++i) {
    seen += c[i];
    if (static_cast<double>(seen) >= want) return UpperEdge(i);
  }
  return UpperEdge(kBuckets - 1);
}

double LatencyHistogram::UpperEdge(int i) { return std::exp2((i + 1) / 4.0) * 1e-6; }


}  // namespace sportsim::server
