#!/usr/bin/env bash
# README command 2: install, build and run every test. Two builds:
#   build/release   — Release (-O2), all tests;
#   build/sanitize  — ASan+UBSan, the core tests.
# Warnings are errors. Ends with CTest's summary.
set -euo pipefail
cd "$(dirname "$0")/.."

bash tools/setup.sh
jobs=$(nproc)
werror=ON   # the test command is what CI runs: warnings are errors here

echo "== release build"
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DTINSMITH_WERROR=$werror >/dev/null
cmake --build build/release -j "$jobs"

echo "== sanitizer build (core tests)"
cmake -S . -B build/sanitize -G Ninja -DCMAKE_BUILD_TYPE=Debug -DTINSMITH_SANITIZE=ON \
  -DTINSMITH_BENCHMARKS=OFF -DTINSMITH_WERROR=$werror >/dev/null
cmake --build build/sanitize -j "$jobs" --target core_tests

echo "== core tests under ASan+UBSan"
ctest --test-dir build/sanitize -L core --output-on-failure -j "$jobs"

echo "== fuzz runs (libFuzzer: CDT 25 s, server request parsers 15 s)"
if command -v clang++ >/dev/null 2>&1; then
  CXX=clang++ cmake -S . -B build/fuzz -G Ninja -DCMAKE_BUILD_TYPE=Debug -DTINSMITH_FUZZ=ON \
    -DTINSMITH_SANITIZE=ON -DTINSMITH_BENCHMARKS=OFF -DTINSMITH_TESTS=ON \
    -DCMAKE_CXX_FLAGS="-O1 -fsanitize=fuzzer-no-link" >/dev/null
  cmake --build build/fuzz -j "$jobs" --target cdt_fuzz request_fuzz
  mkdir -p build/fuzz/corpus build/fuzz/request_corpus
  build/fuzz/tests/fuzz/cdt_fuzz -max_total_time=25 -max_len=2048 -print_final_stats=0 \
    -artifact_prefix=build/fuzz/ build/fuzz/corpus tests/fuzz/seeds 2>&1 | tail -n 3
  build/fuzz/tests/fuzz/request_fuzz -max_total_time=15 -max_len=4096 -print_final_stats=0 \
    -artifact_prefix=build/fuzz/request- build/fuzz/request_corpus tests/fuzz/request_seeds 2>&1 | tail -n 3
else
  echo "clang++ not found: fuzz run skipped"
fi

echo "== all tests (release)"
ctest --test-dir build/release --output-on-failure -j "$jobs"
