#!/usr/bin/env bash
# Cached tiles while slow work runs (issue 22, item 11): wrk fetches the stored
# tiles of an on-demand store (2 threads, 16 connections) alone, then while
# every tile the store lacks is built on demand (all requested at once) and
# four clients post 10 000-point elevation batches back to back. Prints the
# cached tiles' requests/s, p50 and p99 in both runs, and what the slow work
# got (builds, batches, 503s). Needs wrk, curl, jq, python3 and a Release build.
#
#   bash tests/bench/server/slow_work.sh TIN [SECONDS] [TOLERANCE]   (default 10 s, 1 m)
#   e.g. build/release/bin/tinsmith tin config/red-butte.toml -o out/rb.tin first
set -euo pipefail
tin="$(realpath "$1")"
seconds="${2:-10}"
tolerance="${3:-1}"
root="$(cd "$(dirname "$0")/../../.." && pwd)"
. "$root/tests/bench/server/bench_lib.sh"
tinsmith="${TINSMITH:-$root/build/release/bin/tinsmith}"
work="$(mktemp -d)"
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; rm -rf "$work"' EXIT

"$tinsmith" tile "$tin" -o "$work/od.3dtiles" --tolerance "$tolerance" --store-until-zoom 1 -q
port=18282
base="http://127.0.0.1:$port/tilesets/od"

start_server() {
  "$tinsmith" serve "$work/od.3dtiles" --on-demand --port "$port" --quiet 2>"$work/serve.err" &
  pids+=($!)
  wait_port "$port"
}

# Every tile the tileset names, from its JSON and its external tilesets.
all_tiles() {
  python3 - "$base" <<'PY'
import json, sys, urllib.request
base = sys.argv[1]
def walk(url):
    node = json.load(urllib.request.urlopen(url))
    def visit(t):
        uri = t.get("content", {}).get("uri", "")
        if uri.endswith(".glb"): print(uri)
        elif uri.endswith(".json"): walk(base + "/" + uri)
        for c in t.get("children", []): visit(c)
    visit(node["root"])
walk(base + "/tileset.json")
PY
}

stored_paths() {  # the tiles the store holds, as wrk's request list
  sqlite3 "$work/od.3dtiles" "SELECT key FROM media WHERE key LIKE 'tiles/%.glb'" | sed "s|^|/tilesets/od/|"
}

cat >"$work/cached.lua" <<LUA
local paths = {}
for line in io.lines("$work/cached") do paths[#paths + 1] = line end
request = function() return wrk.format("GET", paths[math.random(#paths)]) end
LUA

python3 - >"$work/batch.json" <<'PY'
import json, random
random.seed(3)
print(json.dumps({"points": [[432000 + random.random() * 4000, 4514000 + random.random() * 4000] for _ in range(10000)]}))
PY

row() {
  printf '| %s | %s | %s | %s |\n' "$1" "$(awk '/Requests\/sec/ {printf "%d", $2}' "$2")" \
    "$(awk '$1=="50%" {print $2}' "$2")" "$(awk '$1=="99%" {print $2}' "$2")"
}

start_server
stored_paths >"$work/cached"
echo "store: $(wc -l <"$work/cached") stored tiles, $(all_tiles | wc -l) in the tileset; wrk -t2 -c16 -d${seconds}s; $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"
echo
echo "| run | cached req/s | p50 | p99 |"
echo "|---|---|---|---|"
wrk -t2 -c16 -d"${seconds}s" --latency -s "$work/cached.lua" "http://127.0.0.1:$port" >"$work/alone.txt"
row "cached tiles alone" "$work/alone.txt"

# The slow work, started with wrk: every missing tile at once, and four
# clients posting batches until wrk is done.
all_tiles | grep -v -x -F -f <(sed 's|^/tilesets/od/||' "$work/cached") >"$work/missing" || true
(sleep 0.5; xargs -a "$work/missing" -P 32 -I{} curl -s -o /dev/null -w '%{http_code} %{time_total}\n' "$base/{}" >"$work/builds") &
pids+=($!)
end=$((SECONDS + seconds))
for c in 1 2 3 4; do
  (while [ $SECONDS -lt $end ]; do
    curl -s -o /dev/null -w '%{http_code} %{time_total}\n' -H 'Content-Type: application/json' \
      --data-binary @"$work/batch.json" "$base/elevation"
  done >"$work/batches.$c") &
  pids+=($!)
done
wrk -t2 -c16 -d"${seconds}s" --latency -s "$work/cached.lua" "http://127.0.0.1:$port" >"$work/busy.txt"
wait "${pids[@]:1}" 2>/dev/null || true
row "cached tiles while $(wc -l <"$work/missing") tiles build and 4 clients post batches" "$work/busy.txt"
echo
echo "builds: $(awk '$1 == 200' "$work/builds" | wc -l) answered 200, $(awk '$1 == 503' "$work/builds" | wc -l) 503, slowest $(sort -k2 -n "$work/builds" | tail -1 | cut -d' ' -f2) s"
cat "$work"/batches.* >"$work/batches"
echo "batches: $(awk '$1 == 200' "$work/batches" | wc -l) answered 200, $(awk '$1 == 503' "$work/batches" | wc -l) 503, median $(sort -k2 -n "$work/batches" | awk '{a[NR] = $2} END {print a[int((NR + 1) / 2)]}') s"
