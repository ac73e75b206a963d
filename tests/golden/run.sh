#!/usr/bin/env bash
# Golden outputs of the CLI: each tests/golden/cases/NAME.case is a short
# session of commands on the small inputs in tests/golden/inputs; its
# transcript (each command, its stdout, its stderr, its exit code) must equal
# the committed NAME.expected byte for byte.
#
#   bash tests/golden/run.sh TINSMITH CASE...            # compare
#   TINSMITH_UPDATE_GOLDEN=1 bash tests/golden/run.sh …  # rewrite NAME.expected
#   (or: TINSMITH_UPDATE_GOLDEN=1 ctest -R Golden)
#
# A case line is `tinsmith ARGS…` or `sha256 FILE` (the bytes of an output,
# so a format change shows in review); `#` starts a comment. Each case runs in
# a fresh scratch folder holding a copy of the inputs as `in/` and an empty
# `out/`; in a case line {in} and {out} stand for those two relative paths,
# so no absolute path reaches an output (a .tin records its inputs' paths).
# Durations ("0.012 s", "…seconds": numbers) and peak memory print as #.
set -euo pipefail

if [ $# -lt 2 ]; then
  echo "usage: run.sh TINSMITH CASE..." >&2
  exit 2
fi
tinsmith="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
shift
here="$(cd "$(dirname "$0")" && pwd)"
inputs="$here/inputs"
update="${TINSMITH_UPDATE_GOLDEN:-0}"

normalize() {
  sed -E \
    -e 's#[0-9]+\.[0-9]+ s\b#\# s#g' \
    -e 's#("[a-z_]*(seconds|_s)": )[0-9.eE+-]+#\1\##g' \
    -e 's#[0-9]+(\.[0-9]+)? (MB|MiB) peak#\# \2 peak#g' \
    -e 's#peak memory [0-9]+ MB#peak memory \# MB#g' \
    -e 's#("(cpuSeconds|peakMemoryBytes)": )[0-9.eE+-]+#\1\##g'
}

status=0
for case_file in "$@"; do
  name="$(basename "$case_file" .case)"
  expected="${case_file%.case}.expected"
  out="$(mktemp -d "${TMPDIR:-/tmp}/golden-$name.XXXXXX")"
  cp -r "$inputs" "$out/in"
  mkdir "$out/out"
  transcript="$out.transcript"
  : >"$transcript"
  while IFS= read -r line || [ -n "$line" ]; do
    case "$line" in '' | '#'*) continue ;; esac
    cmd="${line//\{in\}/in}"
    cmd="${cmd//\{out\}/out}"
    read -r -a words <<<"$cmd"
    echo "\$ $line" >>"$transcript"
    case "${words[0]}" in
      tinsmith)
        rc=0
        (cd "$out" && "$tinsmith" "${words[@]:1}" >"$out.stdout" 2>"$out.stderr" </dev/null) || rc=$?
        normalize <"$out.stdout" >>"$transcript"
        if [ -s "$out.stderr" ]; then
          echo "[stderr]" >>"$transcript"
          normalize <"$out.stderr" >>"$transcript"
        fi
        echo "[exit $rc]" >>"$transcript"
        ;;
      sha256)
        if [ -f "$out/${words[1]}" ]; then
          sha256sum "$out/${words[1]}" | cut -d' ' -f1 >>"$transcript"
        else
          echo "(no file)" >>"$transcript"
        fi
        ;;
      *)
        echo "run.sh: $case_file: unknown command '${words[0]}' (tinsmith or sha256)" >&2
        exit 2
        ;;
    esac
  done <"$case_file"

  if [ "$update" = 1 ]; then
    cp "$transcript" "$expected"
    echo "golden $name: written $expected"
  elif [ ! -f "$expected" ]; then
    echo "golden $name: no $expected yet (run with TINSMITH_UPDATE_GOLDEN=1 and review it)" >&2
    status=1
  elif ! diff -u --label "$expected" --label "this run" "$expected" "$transcript"; then
    echo "golden $name: differs (if the change is intended: TINSMITH_UPDATE_GOLDEN=1, then review the diff)" >&2
    status=1
  else
    echo "golden $name: same"
  fi
  rm -rf "$out" "$out.stdout" "$out.stderr" "$transcript"
done
exit $status
