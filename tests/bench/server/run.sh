#!/usr/bin/env bash
# Tile server benchmark (issue 12): wrk on loopback — 2 threads, 64
# connections, random tiles of a store — against `tinsmith serve` and against
# nginx serving the same tiles as files under the same URLs, in one run; then
# single-point elevation queries against tinsmith. Prints a Markdown table:
# requests/s, p50 and p99 latency, and tinsmith's resident memory over its run.
# Needs `bash tools/setup.sh --bench` (wrk, nginx) and a Release build.
#
#   bash tests/bench/server/run.sh STORE.3dtiles [SECONDS]      (default 30)
#   e.g. tinsmith tile out/rb.tin -o out/rb1.3dtiles --tolerance 1 first
set -euo pipefail
store="$(realpath "$1")"
seconds="${2:-30}"
root="$(cd "$(dirname "$0")/../../.." && pwd)"
. "$root/tests/bench/server/bench_lib.sh"
tinsmith="${TINSMITH:-$root/build/release/bin/tinsmith}"
id="$(basename "$store" .3dtiles)"
work="$(mktemp -d)"
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; rm -rf "$work"' EXIT

# The store's files as a directory, for nginx.
mkdir -p "$work/files"
sqlite3 "$store" "SELECT key FROM media" >"$work/keys"
(cd "$work/files" && xargs -a "$work/keys" -n1 dirname | sort -u | xargs mkdir -p &&
  sqlite3 "$store" "SELECT writefile(key, content) FROM media" >/dev/null)
grep '^tiles/' "$work/keys" | sed "s|^|/tilesets/$id/|" >"$work/paths"
tiles=$(wc -l <"$work/paths")
bytes=$(sqlite3 "$store" "SELECT avg(length(content)) FROM media WHERE key LIKE 'tiles/%'")

cat >"$work/random_tiles.lua" <<LUA
local paths = {}
for line in io.lines("$work/paths") do paths[#paths + 1] = line end
math.randomseed(os.time())
request = function() return wrk.format("GET", paths[math.random(#paths)]) end
LUA

write_nginx_conf "$work" 18181 "location /tilesets/$id/ { alias $work/files/; etag on; }"

row() {  # name wrk-output-file
  local rps p50 p99 non2xx
  rps=$(awk '/Requests\/sec/ {printf "%d", $2}' "$2")
  p50=$(awk '$1=="50%" {print $2}' "$2")
  p99=$(awk '$1=="99%" {print $2}' "$2")
  non2xx=$(awk '/Non-2xx/ {print $NF}' "$2")
  printf '| %s | %s | %s | %s | %s |\n' "$1" "$rps" "$p50" "$p99" "${non2xx:-0}"
}

echo "store: $store ($tiles tiles, mean $(printf '%.0f' "$bytes") bytes); wrk -t2 -c64 -d${seconds}s, loopback; $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"
echo
echo "| server | req/s | p50 | p99 | non-2xx |"
echo "|---|---|---|---|---|"

nginx -c "$work/nginx.conf" -e "$work/nginx.err"
wait_port 18181
curl -fsS -o /dev/null "http://127.0.0.1:18181$(head -1 "$work/paths")"
wrk -t2 -c64 -d"${seconds}s" --latency -s "$work/random_tiles.lua" http://127.0.0.1:18181 >"$work/nginx.txt"
kill "$(cat "$work/nginx.pid")"
row "nginx $(nginx -v 2>&1 | sed 's|.*/||') (2 workers, sendfile), tiles" "$work/nginx.txt"

"$tinsmith" serve "$store" --port 18182 --quiet 2>"$work/serve.err" & serve=$!
pids+=("$serve")
wait_port 18182
: >"$work/rss"
(while kill -0 "$serve" 2>/dev/null; do ps -o rss= -p "$serve" >>"$work/rss" || true; sleep 1; done) & pids+=($!)
wrk -t2 -c64 -d"${seconds}s" --latency -s "$work/random_tiles.lua" http://127.0.0.1:18182 >"$work/tinsmith.txt"
row "tinsmith serve, tiles" "$work/tinsmith.txt"

# Single-point elevations at random points of the middle 30 % of the
# project square (points off the TIN answer 404 and count as non-2xx).
read -r x0 y0 x1 y1 < <(curl -fsS http://127.0.0.1:18182/tilesets | python3 -c '
import json, sys
b = json.load(sys.stdin)["tilesets"][0]["bounds"]["project"]
print(*b)')
cat >"$work/random_points.lua" <<LUA
math.randomseed(os.time())
request = function()
  local x = $x0 + ($x1 - $x0) * (0.35 + 0.3 * math.random())
  local y = $y0 + ($y1 - $y0) * (0.35 + 0.3 * math.random())
  return wrk.format("GET", string.format("/tilesets/$id/elevation?x=%.3f&y=%.3f", x, y))
end
LUA
curl -fsS -o /dev/null "http://127.0.0.1:18182/tilesets/$id/elevation?x=$x0&y=$y0" || true  # loads the TIN
wrk -t2 -c64 -d"${seconds}s" --latency -s "$work/random_points.lua" http://127.0.0.1:18182 >"$work/elevation.txt"
row "tinsmith serve, elevation?x=&y=" "$work/elevation.txt"
kill -TERM "$serve"; wait "$serve" || true
echo
sort -n "$work/rss" | awk 'NR==1 {min=$1} {max=$1} END {printf "tinsmith RSS over the run: %.1f MiB at least, %.1f MiB at most\n", min/1024, max/1024}'
echo "tinsmith RSS samples (KiB, 1 s apart): $(tr '\n' ' ' <"$work/rss")"
