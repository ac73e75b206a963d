#!/usr/bin/env bash
# Installs everything tinsmith needs to build, test and run, from Debian
# bookworm packages, plus the pinned npm packages of the JavaScript tile
# checkers (tests/js/package-lock.json) and of the viewer pages that
# `tinsmith serve` serves (server/viewer/package-lock.json: CesiumJS, three,
# 3d-tiles-renderer). Idempotent: installs only what is missing. Needs root
# (or sudo) when a Debian package is missing.
#
#   bash tools/setup.sh           # build, test and run
#   bash tools/setup.sh --bench   # also the tools the benchmarks compare against
set -euo pipefail

bench=0
for arg in "$@"; do
  case "$arg" in
    --bench) bench=1 ;;
    *) echo "setup: unknown option '$arg' (use --bench or nothing)" >&2; exit 2 ;;
  esac
done

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git python3 ca-certificates
  clang libclang-rt-14-dev           # libFuzzer and sanitizer runtimes
  # libraries
  libeigen3-dev libgeographiclib-dev libopenexr-dev libtinygltf-dev libdraco-dev
  libgdal-dev gdal-bin libproj-dev proj-data libsqlite3-dev sqlite3 libtomlplusplus-dev libcli11-dev
  nlohmann-json3-dev
  libboost-dev zlib1g-dev libbrotli-dev  # the server: Beast/Asio (Debian's default Boost), gzip, brotli
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev libcgal-dev
  chromium                           # tests/js/cesium_smoke.mjs renders in it
  slurmctld slurmd slurm-client munge  # the Slurm tests' one-node cluster (tests/slurm); nothing starts at install
)
# tests/js runs on node; Debian's only when the machine has none (an image's
# own, newer node is kept).
command -v node >/dev/null 2>&1 || packages+=(nodejs npm)
if [ "$bench" -eq 1 ]; then
  packages+=(
    # benchmark-only references (tests/bench/): GRASS GIS v.surf.rst, and
    # python3 GDAL + NumPy for the error evaluator
    grass-core python3-gdal python3-numpy
    # the server's benchmarks (tests/bench/server/): load generator, the
    # static server it is measured against, the cpp-httplib prototype
    wrk nginx-light libcpp-httplib-dev
  )
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

did=()
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  did+=("installed ${#missing[@]} Debian packages (${missing[*]})")
fi

# The npm packages of the tile checkers and of the viewer, exactly as
# locked; again only when node_modules is missing or older than the lock.
root="$(cd "$(dirname "$0")/.." && pwd)"
for dir in tests/js server/viewer; do
  [ -f "$root/$dir/package-lock.json" ] || continue  # not copied (the Docker builder's first step)
  if [ ! -d "$root/$dir/node_modules" ] || [ "$root/$dir/node_modules/.package-lock.json" -ot "$root/$dir/package-lock.json" ]; then
    npm ci --prefix "$root/$dir" --no-audit --no-fund --loglevel=error >/dev/null
    did+=("ran npm ci in $dir")
  fi
done

if [ ${#did[@]} -eq 0 ]; then
  echo "setup: nothing to do (all ${#packages[@]} Debian packages installed, tests/js and server/viewer node_modules up to date)"
else
  line=""
  for d in "${did[@]}"; do line+="${line:+; }$d"; done
  echo "setup: $line"
fi
