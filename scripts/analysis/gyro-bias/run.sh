#!/usr/bin/env bash
# What a gyro's bias shift does to the estimate before anything flags it (docs/results/dropout.md):
# the 8 test flights of the `paper` preset with seeds 11 and 12 (none trained or fitted any shipped
# estimator; made by scripts/analysis/beta-by-gust/run.sh, or here if missing) flown through the
# estimator
# (`hil-sim run --firmware host`) once per gyro and bias size, with the bias switched on for 10 s
# every 25 s from 25 s into the flight, each with 15 s of the flight after it; then table.py: per gyro and size, over every onset, the
# largest departure from the fault-free run of an estimate that carries no flag, and the onsets
# whose unflagged departure passes the silent-error sizes (2° α, 1° β).
#
#   scripts/analysis/gyro-bias/run.sh [--aircraft NAME] [--bin DIR] [--out DIR]
#   scripts/analysis/gyro-bias/run.sh --out docs/results    # the page
#
# --bin DIR takes hil-sim from another build's release directory (to compare two estimators; a
# relative DIR, like --out, is taken from the checkout's root). The flights of seeds 11-18 are made
# if missing (all eight, as the other analyses use them).
# Needs the aircraft's release build (target/ or target/NAME) and the project's .venv
# (scripts/bootstrap). Scratch in out/gyro-bias/NAME/BUILD/; about 1 min on 2 cores.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh  # default_aircraft, aircraft_target, paper_test_flights, host_run
command="scripts/analysis/gyro-bias/run.sh${*:+ $*}"
name="$default_aircraft"
dest=""
bin=""
while [ $# -gt 0 ]; do
  case "$1" in
    --aircraft|--out|--bin)
      [ $# -ge 2 ] || { echo "gyro-bias: $1 needs a value (see the header of $0)" >&2; exit 2; }
      case "$1" in --aircraft) name="$2" ;; --out) dest="$2" ;; --bin) bin="$2" ;; esac
      shift 2 ;;
    *) echo "gyro-bias: unknown argument $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
aircraft_target "$name"
build="${bin:-default}"
bin="${bin:-$target/release}"
[ -x "$bin/hil-sim" ] || { echo "gyro-bias: no $bin/hil-sim: build $name's release build first (header)" >&2; exit 2; }
[ -z "$dest" ] || [ -d "$dest" ] || { echo "gyro-bias: --out $dest is not a directory" >&2; exit 2; }
paper_test_flights "$name"
flights=("out/turb/$name-11"/test_*.csv "out/turb/$name-12"/test_*.csv)
work="out/gyro-bias/$name/$(echo "$build" | tr '/' '_')"
mkdir -p "$work"
for csv in "${flights[@]}"; do
  flight="$(basename "$(dirname "$csv")")/$(basename "$csv" .csv)"
  last="$(tail -n 1 "$csv" | cut -d, -f1)"
  for gyro in p q r; do
    for size in 0.03 0.06 0.1 0.2; do
      faults=()
      for ((t = 25; t + 25 <= ${last%.*}; t += 25)); do
        faults+=(--fault "bias:gyro_${gyro}_rps=${size}@${t}+10")
      done
      host_run "$work/$flight/$gyro-$size" "$csv" --aircraft "$name" "${faults[@]}"
    done
  done
  echo "gyro-bias: $flight flown" >&2
done
.venv/bin/python scripts/analysis/gyro-bias/table.py "$name" "$work" "$command" > "$work/gyro-bias.md"
if [ -n "$dest" ]; then
  mv "$work/gyro-bias.md" "$dest/gyro-bias.md"
  echo "wrote $dest/gyro-bias.md" >&2
else
  cat "$work/gyro-bias.md"
fi
