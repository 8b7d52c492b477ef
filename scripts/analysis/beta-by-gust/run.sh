#!/usr/bin/env bash
# β (and α) error against the turbulence each test flight flew, every aircraft beside the F-16
# (docs/results/c172p.md, "β and turbulence"; docs/results/f15.md): the `paper` preset's test
# flights with seeds 11-18, none of which trained any shipped estimator, each aircraft's shipped
# estimator on its own (`trainer eval --json`, beside each dataset as DIR.eval.json), then table.py.
#
#   scripts/analysis/beta-by-gust/run.sh               # f16 and c172p
#   scripts/analysis/beta-by-gust/run.sh f16 c172p f15 # the aircraft named, in that order
#
# Needs each aircraft's release build (the F-16's in target/, another's in target/NAME:
# ESTIMATOR_AIRCRAFT=NAME CARGO_TARGET_DIR=target/NAME cargo build --release -p hil-sim -p trainer)
# and the project's .venv (scripts/bootstrap). Writes into out/turb/ (flights kept; an evaluation
# redone when its build is newer); about 1 min per aircraft on 2 cores.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh  # default_aircraft, analysis_binaries, paper_test_flights
[ $# -gt 0 ] || set -- "$default_aircraft" c172p
analysis_aircraft "$@"  # every name checked before any aircraft's work starts
[ -x .venv/bin/python ] || { echo "beta-by-gust: no .venv: run scripts/bootstrap" >&2; exit 2; }
args=()
for name in "$@"; do
  analysis_binaries "$name" hil-sim trainer
  paper_test_flights "$name"
  for d in "${flight_dirs[@]}"; do
    if [ ! "$d.eval.json" -nt "$bin/trainer" ]; then
      "$bin/trainer" eval --aircraft "$name" --data "$d" --json > "$d.eval.json.new"
      mv "$d.eval.json.new" "$d.eval.json"
    fi
  done
  args+=("$name=$(IFS=,; echo "${flight_dirs[*]}")")
done
.venv/bin/python scripts/analysis/beta-by-gust/table.py "${args[@]}"
