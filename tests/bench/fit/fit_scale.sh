#!/usr/bin/env bash
# Scale of the multilevel fitter, side by side for one or more builds of
# fit_scale_bench (e.g. before and after a change), Franke points at 0.1 %
# tolerance. Each configuration runs 3 times, interleaved; the fastest fit
# (wall) is kept with its CPU time; peak RSS is the largest of the 3.
#
#   bash tests/bench/fit/fit_scale.sh BENCH [BENCH ...]      (N from $SIZES)
#   SIZES="100000 1000000" THREADS=1 bash tests/bench/fit/fit_scale.sh ...
set -euo pipefail
SIZES=${SIZES:-"100000 1000000 2000000 4000000"}
THREADS=${THREADS:-0}
printf '%-60s %8s %8s %8s %9s %7s %9s\n' binary points "fit s" "cpu s" "RSS MB" "B/pt" vertices
for n in $SIZES; do
  declare -A best=() cpu=() rss=() verts=()
  for run in 1 2 3; do
    for bin in "$@"; do
      line=$("$bin" franke "$n" --threads "$THREADS" | tail -1)
      wall=$(sed -E 's/.* fit ([0-9.]+) s .*/\1/' <<<"$line")
      c=$(sed -E 's/.*\(cpu ([0-9.]+) s\).*/\1/' <<<"$line")
      r=$(sed -E 's/.*peak RSS ([0-9.]+) MB.*/\1/' <<<"$line")
      v=$(sed -E 's/.* vertices ([0-9]+) .*/\1/' <<<"$line")
      if [[ -z "${best[$bin]:-}" ]] || awk "BEGIN{exit !($wall < ${best[$bin]})}"; then
        best[$bin]=$wall
        cpu[$bin]=$c
      fi
      if [[ -z "${rss[$bin]:-}" ]] || awk "BEGIN{exit !($r > ${rss[$bin]})}"; then rss[$bin]=$r; fi
      verts[$bin]=$v
    done
  done
  for bin in "$@"; do
    bpp=$(awk "BEGIN{printf \"%.0f\", ${rss[$bin]} * 1048576 / $n}")
    printf '%-60s %8s %8s %8s %9s %7s %9s\n' "$bin" "$n" "${best[$bin]}" "${cpu[$bin]}" "${rss[$bin]}" "$bpp" "${verts[$bin]}"
  done
  unset best cpu rss verts
done
