#!/usr/bin/env bash
# The HTTP layer measurement behind docs/server-http-layer.md: the prototypes
# beside it and nginx serve the same in-memory/file body of BYTES bytes over
# keep-alive on loopback; wrk (2 threads, 64 connections, 10 s) measures each
# in turn, in one run. Needs `bash tools/setup.sh --bench` (wrk, nginx) and
# libboost-dev, libcpp-httplib-dev.
#
#   bash tests/bench/server/http_layer.sh [BYTES ...]     (default 1024 10240 102400)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
. "$here/bench_lib.sh"
work="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(1024 10240 102400)

g++ -std=c++20 -O2 -o "$work/beast" "$here/proto_beast.cpp" -pthread
g++ -std=c++20 -O2 -o "$work/httplib" "$here/proto_httplib.cpp" -pthread $(pkg-config --cflags --libs cpp-httplib)

measure() {  # name port
  wrk -t2 -c64 -d10s --latency "http://127.0.0.1:$2/body" >"$work/wrk.txt"
  rps=$(awk '/Requests\/sec/ {print $2}' "$work/wrk.txt")
  p50=$(awk '$1=="50%" {print $2}' "$work/wrk.txt")
  p99=$(awk '$1=="99%" {print $2}' "$work/wrk.txt")
  printf '| %s | %s | %s | %s | %s |\n' "$bytes" "$1" "$rps" "$p50" "$p99"
}

echo "| body bytes | server | req/s | p50 | p99 |"
echo "|---|---|---|---|---|"
for bytes in "${sizes[@]}"; do
  head -c "$bytes" /dev/zero | tr '\0' x >"$work/body"
  write_nginx_conf "$work" 18081 "root $work;"
  nginx -c "$work/nginx.conf" -e "$work/nginx.err"
  wait_port 18081; measure "nginx 1.22 (2 workers, sendfile)" 18081
  kill "$(cat "$work/nginx.pid")"
  "$work/beast" 18082 "$bytes" 2 & pid=$!
  wait_port 18082; measure "Boost.Beast 1.74 / Asio (2 io_contexts)" 18082; kill $pid; wait $pid 2>/dev/null || true
  "$work/httplib" 18083 "$bytes" 64 & pid=$!
  wait_port 18083; measure "cpp-httplib 0.11 (64 threads, nodelay)" 18083; kill $pid; wait $pid 2>/dev/null || true
done
