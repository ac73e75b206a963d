#!/usr/bin/env bash
# Installs everything tinsmith needs to build, test and run, from Debian
# bookworm packages only. Idempotent: installs only what is missing. Needs root
# (or sudo) when something is missing.
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
  libgdal-dev gdal-bin libsqlite3-dev sqlite3 libtomlplusplus-dev libcli11-dev
  libcpp-httplib-dev nlohmann-json3-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev libcgal-dev
)
if [ "$bench" -eq 1 ]; then
  packages+=(
    # benchmark-only references (tests/bench/): GRASS GIS v.surf.rst, and
    # python3 GDAL + NumPy for the error evaluator
    grass-core python3-gdal python3-numpy
  )
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} Debian packages already installed"
  exit 0
fi

echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
