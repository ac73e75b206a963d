#!/usr/bin/env bash
# Run the torture cases through the real command line.
# usage: run_cases.sh TINSMITH_BINARY [CASES_DIR] [CASE_NAME_REGEX] [WRAPPER...]
#   CASES_DIR defaults to a fresh temp dir filled by gen_cases.py.
#   WRAPPER (optional, e.g. "valgrind -q --error-exitcode=99") prefixes the tin command.
# Each case: tin -> validate -> export obj -> check_tin.py (good input), or for bad
# input: the documented exit code, an "ERROR:" message, no crash/hang, no output file.
# Prints one line per case; exits 1 if any case FAILs.
set -u
BIN=$(readlink -f "${1:?usage: run_cases.sh TINSMITH_BINARY [CASES_DIR] [REGEX] [WRAPPER...]}")
HERE=$(cd "$(dirname "$0")" && pwd)
CASES=${2:-}
FILTER=${3:-.}
shift $(( $# < 3 ? $# : 3 ))
WRAP=("$@")
CHECK=${CHECK_TIN:-$(readlink -f "$HERE/../../../shared/tools/check_tin.py")}
TMO=${TORTURE_TIMEOUT:-60}
if [ -z "$CASES" ]; then
  CASES=$(mktemp -d)
  python3 "$HERE/gen_cases.py" "$CASES" >/dev/null || { echo "generator failed"; exit 2; }
fi
[ -f "$CASES/cases.tsv" ] || python3 "$HERE/gen_cases.py" "$CASES" >/dev/null
WORK=$(mktemp -d)
nfail=0; n=0
while IFS=$'\t' read -r name expect snap tol bl; do
  [[ "$name" =~ $FILTER ]] || continue
  n=$((n+1))
  d="$CASES/$name"; w="$WORK/$name"; mkdir -p "$w"
  args=(tin --points "$d/P.xyz" -o "$w/out.tin")
  [ "$bl" != "-" ] && args+=(--breaklines "$d/$bl")
  [ "$snap" != "0.0" ] && args+=(--snap "$snap")
  t0=$(date +%s.%N)
  timeout "$TMO" "${WRAP[@]}" "$BIN" "${args[@]}" >"$w/tin.out" 2>"$w/tin.err" </dev/null
  rc=$?
  secs=$(echo "$(date +%s.%N) - $t0" | bc)
  secs=$(printf '%.2f' "$secs")
  err1=$(grep -m1 -E 'ERROR|error|Sanitizer|Invalid|Assert' "$w/tin.err" | cut -c1-220)
  fail=""
  if [ "$expect" = ok ]; then
    if [ $rc -ne 0 ]; then
      fail="tin exit $rc ($err1)"
    else
      vout=$(timeout "$TMO" "$BIN" validate "$w/out.tin" 2>&1); vrc=$?
      if [ $vrc -ne 0 ]; then fail="validate exit $vrc: $(echo "$vout" | grep -v valid | head -3 | tr '\n' ' ' | cut -c1-300)"; fi
      if timeout "$TMO" "$BIN" export "$w/out.tin" --format obj -o "$w/out.obj" >"$w/export.log" 2>&1; then
        cb=(); [ -f "$d/B.geojson" ] && cb=("$d/B.geojson")
        cout=$(timeout 600 python3 "$CHECK" "$w/out.obj" "$d/P.xyz" "${cb[@]}" --tol "$tol" 2>&1); crc=$?
        if [ $crc -ne 0 ] && [ "$(echo "$cout" | grep -c .)" -eq 1 ] && echo "$cout" | grep -q '^FAIL: triangle area' \
           && python3 "$HERE/exact_area.py" "$w/out.obj" >/dev/null; then
          cout="ok (check_tin float area false positive; exact area = hull area)"; crc=0
        fi
        if [ $crc -ne 0 ]; then fail="${fail:+$fail; }check_tin: $(echo "$cout" | head -4 | tr '\n' ' ' | cut -c1-300)"; fi
      else
        fail="${fail:+$fail; }export failed: $(head -2 "$w/export.log" | tr '\n' ' ')"
      fi
    fi
  else
    if [ $rc -eq 124 ]; then fail="hang (timeout ${TMO}s)"
    elif [ $rc -ge 128 ] || [ $rc -eq 70 ]; then fail="crash/internal, exit $rc ($err1)"
    elif [ $rc -ne "$expect" ]; then fail="exit $rc, expected $expect ($err1)"
    elif ! grep -q '^ERROR' "$w/tin.err"; then fail="exit $rc but no ERROR message"
    fi
    [ -e "$w/out.tin" ] && fail="${fail:+$fail; }output file left behind"
    ls "$w" | grep -q -v -E '^(tin\.out|tin\.err)$' && [ ! -e "$w/out.tin" ] && fail="${fail:+$fail; }stray file: $(ls "$w" | tr '\n' ' ')"
  fi
  san=$(grep -m1 -E 'runtime error|AddressSanitizer|LeakSanitizer' "$w/tin.err" | cut -c1-200)
  [ -n "$san" ] && fail="${fail:+$fail; }sanitizer: $san"
  if [ -n "$fail" ]; then
    nfail=$((nfail+1)); printf 'FAIL %-32s %6ss  %s\n' "$name" "$secs" "$fail"
  else
    printf 'ok   %-32s %6ss  %s\n' "$name" "$secs" "$( [ "$expect" = ok ] && echo "$cout" | head -1 | cut -c1-100 || echo "exit $rc: $err1" | cut -c1-140)"
  fi
done < "$CASES/cases.tsv"
echo "$((n-nfail)) ok, $nfail FAIL of $n (work dir $WORK)"
[ $nfail -eq 0 ]
