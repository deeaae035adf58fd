#!/usr/bin/env bash
# Paired timing of two commands: A and B run alternately (A B A B …), each
# as a whole process, and each pair's CPU seconds (user + system, from
# /usr/bin/time) and the ratio A/B are printed, then the median ratio.
# Pairs rather than two series, so that a machine whose speed drifts
# between runs (a shared one) still gives a fair ratio.
#
#   experiments/bench/pair.sh [-n RUNS] [--warmup W] [--timeout S] --vs 'B' -- A [ARG …]
#
# A is a command and its arguments; B one string, split by the shell.
# `--timeout` is accepted and ignored (a run is never cut short). Run from
# the repository root, with `jamkit` on PATH where the commands name it.
set -euo pipefail
runs=5 warmup=1 b=""
while [ $# -gt 0 ]; do
  case "$1" in
    -n) runs=$2; shift 2 ;;
    --warmup) warmup=$2; shift 2 ;;
    --timeout) shift 2 ;;
    --vs) b=$2; shift 2 ;;
    --) shift; break ;;
    *) echo "pair.sh: unknown option $1 (see the usage at the top of the script)" >&2; exit 2 ;;
  esac
done
if [ -z "$b" ] || [ $# -eq 0 ]; then
  echo "pair.sh: give --vs 'B' and, after --, the command A" >&2
  exit 2
fi
times=$(mktemp)
trap 'rm -f "$times"' EXIT
cpu() { # CPU seconds of one run of the command "$@"
  /usr/bin/time -f '%U %S' -o "$times" "$@" > /dev/null 2>&1 || true
  awk '{ print $1 + $2 }' "$times"
}
for _ in $(seq "$warmup"); do cpu "$@" > /dev/null; cpu sh -c "exec $b" > /dev/null; done
ratios=()
for k in $(seq "$runs"); do
  ta=$(cpu "$@")
  tb=$(cpu sh -c "exec $b")
  r=$(awk -v a="$ta" -v b="$tb" 'BEGIN { if (b > 0) printf "%.3f", a / b; else print "inf" }')
  ratios+=("$r")
  echo "pair $k: A $ta s, B $tb s, A/B $r"
done
printf '%s\n' "${ratios[@]}" | sort -g | awk '{ v[NR] = $1 } END {
  m = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
  printf "median A/B %.3f (min %.3f, max %.3f, %d pairs)\n", m, v[1], v[NR], NR }'
