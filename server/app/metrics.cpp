#include "server/app/metrics.hpp"

#include <cstdio>
#include <string>

namespace tinsmith::server {
namespace {

/// A metric with one value, as the exposition format writes it: its HELP and
/// TYPE lines, then `name value`.
void appendSingle(std::string& out, const char* name, const char* type, const char* help,
                  const std::string& value) {
  out.append("# HELP ").append(name).append(" ").append(help).append("\n");
  out.append("# TYPE ").append(name).append(" ").append(type).append("\n");
  out.append(name).append(" ").append(value).append("\n");
}

}  // namespace

std::size_t Metrics::statusSlot(int status) {
  for (std::size_t i = 0; i + 1 < kStatusSlots; ++i)
    if (kStatuses[i] == status) return i;
  return kStatusSlots - 1;
}

void Metrics::countRequest(RouteKind route, int status, std::uint64_t bytes,
                           std::chrono::steady_clock::duration elapsed) {
  const auto r = static_cast<std::size_t>(route);
  requests_[r][statusSlot(status)].fetch_add(1, kRelaxed);
  bytes_[r].fetch_add(bytes, kRelaxed);
  const double seconds = std::chrono::duration<double>(elapsed).count();
  std::size_t bucket = 0;
  while (bucket < kBuckets.size() && seconds > kBuckets[bucket]) ++bucket;
  latency_[bucket].fetch_add(1, kRelaxed);
  latencyNanos_.fetch_add(
      static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(elapsed).count()),
      kRelaxed);
}

std::uint64_t Metrics::requests(RouteKind route, int status) const {
  return requests_[static_cast<std::size_t>(route)][statusSlot(status)].load(kRelaxed);
}

std::string Metrics::prometheusText() const {
  std::string out;
  char line[256];
  out += "# HELP tinsmith_http_requests_total Requests answered, by route and status.\n"
         "# TYPE tinsmith_http_requests_total counter\n";
  for (int r = 0; r < kRouteKinds; ++r)
    for (std::size_t s = 0; s < kStatusSlots; ++s) {
      const auto n = requests_[static_cast<std::size_t>(r)][s].load(kRelaxed);
      if (n == 0) continue;
      const std::string status = s + 1 < kStatusSlots ? std::to_string(kStatuses[s]) : "other";
      std::snprintf(line, sizeof line, "tinsmith_http_requests_total{route=\"%s\",status=\"%s\"} %llu\n",
                    std::string(routeName(static_cast<RouteKind>(r))).c_str(), status.c_str(),
                    static_cast<unsigned long long>(n));
      out += line;
    }
  out += "# HELP tinsmith_http_response_bytes_total Bytes written (headers and bodies), by route.\n"
         "# TYPE tinsmith_http_response_bytes_total counter\n";
  for (int r = 0; r < kRouteKinds; ++r) {
    std::snprintf(line, sizeof line, "tinsmith_http_response_bytes_total{route=\"%s\"} %llu\n",
                  std::string(routeName(static_cast<RouteKind>(r))).c_str(),
                  static_cast<unsigned long long>(bytes_[static_cast<std::size_t>(r)].load(kRelaxed)));
    out += line;
  }
  out += "# HELP tinsmith_http_request_duration_seconds From the request read to its response written.\n"
         "# TYPE tinsmith_http_request_duration_seconds histogram\n";
  std::uint64_t cumulative = 0;
  for (std::size_t b = 0; b <= kBuckets.size(); ++b) {
    cumulative += latency_[b].load(kRelaxed);
    if (b < kBuckets.size())
      std::snprintf(line, sizeof line, "tinsmith_http_request_duration_seconds_bucket{le=\"%g\"} %llu\n",
                    kBuckets[b], static_cast<unsigned long long>(cumulative));
    else
      std::snprintf(line, sizeof line, "tinsmith_http_request_duration_seconds_bucket{le=\"+Inf\"} %llu\n",
                    static_cast<unsigned long long>(cumulative));
    out += line;
  }
  std::snprintf(line, sizeof line,
                "tinsmith_http_request_duration_seconds_sum %.9f\n"
                "tinsmith_http_request_duration_seconds_count %llu\n",
                static_cast<double>(latencyNanos_.load(kRelaxed)) * 1e-9,
                static_cast<unsigned long long>(cumulative));
  out += line;
  appendSingle(out, "tinsmith_tile_cache_hits_total", "counter",
               "Tiles and tileset files served from memory.",
               std::to_string(cacheHits_.load(kRelaxed)));
  appendSingle(out, "tinsmith_tile_cache_misses_total", "counter",
               "Tiles and tileset files read from a store.",
               std::to_string(cacheMisses_.load(kRelaxed)));
  appendSingle(out, "tinsmith_open_connections", "gauge", "Connections open now.",
               std::to_string(static_cast<long long>(openConnections_.load(kRelaxed))));
  appendSingle(out, "tinsmith_tiles_built_on_demand_total", "counter",
               "Tiles built from a store's TIN (--on-demand), each once.",
               std::to_string(tilesBuilt_.load(kRelaxed)));
  appendSingle(out, "tinsmith_on_demand_waits_total", "counter",
               "Requests that waited for a tile another request was building.",
               std::to_string(buildWaits_.load(kRelaxed)));
  appendSingle(out, "tinsmith_on_demand_build_seconds_total", "counter",
               "Time spent building tiles on demand.",
               std::to_string(static_cast<double>(buildNanos_.load(kRelaxed)) * 1e-9));  // %f
  if (const WorkPool* pool = pool_.load(kRelaxed)) {
    const WorkPool::Stats work = pool->stats();
    appendSingle(out, "tinsmith_work_workers", "gauge",
                 "Worker threads for slow requests (on-demand builds, large batches).",
                 std::to_string(work.workers));
    appendSingle(out, "tinsmith_work_running", "gauge", "Slow requests on a worker now.",
                 std::to_string(work.running));
    appendSingle(out, "tinsmith_work_waiting", "gauge",
                 "Slow requests queued for a worker now (at most --queue beyond the idle ones).",
                 std::to_string(work.waiting));
    appendSingle(out, "tinsmith_work_queued_total", "counter",
                 "Slow requests handed to the workers.", std::to_string(work.queued));
    appendSingle(out, "tinsmith_work_rejected_total", "counter",
                 "Slow requests refused with 503 because the queue was full.",
                 std::to_string(work.rejected));
  }
  return out;
}

}  // namespace tinsmith::server
