// The server's counters, exposed as Prometheus text (/metrics): requests by
// route and status, a latency histogram, response bytes, tile cache hits and
// misses, open connections, tiles built on demand, the worker pool's queue
// (server/app/work_pool.hpp). Lock-free (relaxed atomics): a scrape sees each
// counter whole, not all of them at one instant.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>

#include "server/app/work_pool.hpp"
#include "server/http/route.hpp"

namespace tinsmith::server {

class Metrics {
 public:
  /// The statuses counted by name; any other lands in "other".
  static constexpr std::array<int, 17> kStatuses{200, 204, 206, 304, 400, 404, 405, 408, 412,
                                                 413, 414, 416, 431, 500, 501, 503, 505};
  /// Upper bounds of the latency buckets, seconds (then +Inf).
  static constexpr std::array<double, 14> kBuckets{0.0001, 0.00025, 0.0005, 0.001, 0.0025,
                                                   0.005,  0.01,    0.025,  0.05,  0.1,
                                                   0.25,   0.5,     1.0,    5.0};

  void countRequest(RouteKind route, int status, std::uint64_t bytes,
                    std::chrono::steady_clock::duration elapsed);
  void countCache(bool hit) { (hit ? cacheHits_ : cacheMisses_).fetch_add(1, kRelaxed); }
  void countConnection(int delta) { openConnections_.fetch_add(delta, kRelaxed); }
  /// A tile built on demand, and how long it took.
  void countTileBuilt(std::chrono::steady_clock::duration took) {
    tilesBuilt_.fetch_add(1, kRelaxed);
    buildNanos_.fetch_add(static_cast<std::uint64_t>(std::chrono::nanoseconds(took).count()),
                          kRelaxed);
  }
  /// A request that waited for a build another request started.
  void countBuildWait() { buildWaits_.fetch_add(1, kRelaxed); }
  [[nodiscard]] std::uint64_t tilesBuilt() const { return tilesBuilt_.load(kRelaxed); }
  /// The pool whose queue the text reports (null: none); it must outlive
  /// this, or be unset first.
  void watchPool(const WorkPool* pool) { pool_.store(pool, kRelaxed); }

  /// Requests counted for (route, status) so far (for tests).
  [[nodiscard]] std::uint64_t requests(RouteKind route, int status) const;
  [[nodiscard]] std::int64_t openConnections() const { return openConnections_.load(kRelaxed); }

  /// The Prometheus text exposition (format 0.0.4).
  [[nodiscard]] std::string prometheusText() const;

 private:
  static constexpr auto kRelaxed = std::memory_order_relaxed;
  static constexpr std::size_t kStatusSlots = kStatuses.size() + 1;  // + "other"
  [[nodiscard]] static std::size_t statusSlot(int status);

  std::array<std::array<std::atomic<std::uint64_t>, kStatusSlots>, kRouteKinds> requests_{};
  std::array<std::atomic<std::uint64_t>, kRouteKinds> bytes_{};
  std::array<std::atomic<std::uint64_t>, kBuckets.size() + 1> latency_{};
  std::atomic<std::uint64_t> latencyNanos_{0};
  std::atomic<std::uint64_t> cacheHits_{0}, cacheMisses_{0};
  std::atomic<std::int64_t> openConnections_{0};
  std::atomic<std::uint64_t> tilesBuilt_{0}, buildWaits_{0}, buildNanos_{0};
  std::atomic<const WorkPool*> pool_{nullptr};
};

}  // namespace tinsmith::server
