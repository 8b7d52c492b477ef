#!/usr/bin/env bash
# What the normal force shows (docs/results/force-residual.md): frame by frame, the body-z specific
# force the IMU measures (moved to the CG) beside the one the air-data filter's force model gives at
# the flight's true air-data point (JSBSim's α, β, Mach, airspeed, dynamic pressure, mass and rates)
# and at the filter's own estimate (`trainer eval-filter --frames`). On the `paper` preset's test
# cards with seed S flown on JSBSim's F-16 and on each development variant (out/sigma/aircraft/*,
# made there if missing): whether the model explains the force the plant makes, and how much of the
# filter's α error the normal force shows, by dynamic pressure; the shipped estimator's α beside it
# (`hil-sim run --firmware host`). table.py writes the page and its plot (the largest slow-flight
# miss on JSBSim's F-16).
#
#   scripts/analysis/force-residual/run.sh [--seed S] [--out DIR]
#   scripts/analysis/force-residual/run.sh --out docs/results    # the page and its plot (seed 31)
#
# Needs the F-16's release build (cargo build --release -p trainer -p hil-sim) and the project's .venv
# (scripts/bootstrap). Scratch in out/force-residual/S/; about a minute on 2 cores the first time (the
# cards flown, each flight stepped through the estimator), seconds after.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
command="scripts/analysis/force-residual/run.sh${*:+ $*}"
seed=31
dest=""
while [ $# -gt 0 ]; do
  case "$1" in
    --seed|--out)
      [ $# -ge 2 ] || { echo "force-residual: $1 needs a value (see the header of $0)" >&2; exit 2; }
      if [ "$1" = --seed ]; then seed="$2"; else dest="$2"; fi
      shift 2 ;;
    *) echo "force-residual: unknown argument $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
[[ "$seed" =~ ^[0-9]+$ ]] || { echo "force-residual: --seed $seed is not a whole number" >&2; exit 2; }
[ -z "$dest" ] || [ -d "$dest" ] || { echo "force-residual: --out $dest is not a directory" >&2; exit 2; }
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh  # default_aircraft, analysis_binaries, host_run, development_cards
analysis_binaries "$default_aircraft" hil-sim trainer
[ -x .venv/bin/python ] || { echo "force-residual: no .venv: run scripts/bootstrap" >&2; exit 2; }
work="out/force-residual/$seed"
development_cards "$work/cards" "$seed"
mkdir -p "$work/frames"
for n in "${card_names[@]}"; do
  d="$work/cards/$n"
  if [ ! "$work/frames/$n.csv" -nt "$bin/trainer" ] || [ ! "$work/frames/$n.csv" -nt "$d/manifest.json" ]; then
    "$bin/trainer" eval-filter --data "$d" --frames "$work/frames/$n.csv" --json > "$work/frames/$n.json"
  fi
  for csv in "$d"/test_*.csv; do
    host_run "$work/runs/$n/$(basename "$csv" .csv)" "$csv"
  done
  echo "force-residual: $n done" >&2
done
# The plot is drawn only when a slow-flight miss is found: none left from an earlier run.
rm -f "$work/force-residual.png"
TRAINER="$bin/trainer" .venv/bin/python scripts/analysis/force-residual/table.py "$work" "$command" "$seed" "${card_names[@]}"
if [ -n "$dest" ]; then
  cp "$work/force-residual.md" "$dest/"
  [ ! -f "$work/force-residual.png" ] || cp "$work/force-residual.png" "$dest/"
  echo "force-residual: wrote $dest/force-residual.md and .png" >&2
fi
