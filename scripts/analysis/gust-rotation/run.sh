#!/usr/bin/env bash
# What the turbulence's rotation costs each shipped estimator (docs/results/beta-floor.md, "What the
# gusts' rotation costs"). JSBSim's Milspec turbulence turns the air as well as moving it (a pitch
# rate from the vertical gust's change, a yaw rate from the lateral one's, a roll rate of its own),
# and the aerodynamics read the body rates less those: a force and moment no gyro measures. The
# `paper` preset's four test flights (seed 1) are flown on the aircraft's own model, on the same
# model whose aerodynamic rate terms read the body rates (aerodynamics.toml), and on the model that
# reads them in its flight controls too (everywhere.toml: the F-16's dampers feed back the
# air-relative rates), each through scripts/airframe-variant, with the same maneuvers, winds and
# sensor errors; the shipped estimator (`trainer eval --json`, as trained: with the rotation) is
# scored on all three, and table.py prints the α / β MAE per flight.
#
#   scripts/analysis/gust-rotation/run.sh                 # f16
#   scripts/analysis/gust-rotation/run.sh f16 c172p f15   # the aircraft named, in that order
#
# Needs each aircraft's release build (the F-16's in target/, another's in target/NAME:
# ESTIMATOR_AIRCRAFT=NAME CARGO_TARGET_DIR=target/NAME cargo build --release -p hil-sim -p trainer)
# and the project's .venv (scripts/bootstrap). Writes out/gust-rotation/NAME/; about 1 min per
# aircraft on 2 cores.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh  # default_aircraft, analysis_binaries, aircraft_model
[ $# -gt 0 ] || set -- "$default_aircraft"
analysis_aircraft "$@"  # every name checked before any aircraft's work starts
[ -x .venv/bin/python ] || { echo "gust-rotation: no .venv: run scripts/bootstrap" >&2; exit 2; }
here=scripts/analysis/gust-rotation
export HIL_PYTHON="${HIL_PYTHON:-$root/.venv/bin/python}"
args=()
for name in "$@"; do
  analysis_binaries "$name" hil-sim trainer
  model=$(aircraft_model "$name")
  out="out/gust-rotation/$name"
  rm -rf "$out"
  mkdir -p "$out"
  "$bin/hil-sim" generate --aircraft "$name" --preset paper --test-only --seed 1 --out "$out/model" > /dev/null
  for v in aerodynamics everywhere; do
    scripts/airframe-variant "$here/$v.toml" --model "$model" --out "$out/aircraft-$v" > /dev/null
    "$bin/hil-sim" generate --aircraft "$name" --preset paper --test-only --seed 1 --aircraft-dir "$out/aircraft-$v" \
      --out "$out/$v" > /dev/null
  done
  for d in model aerodynamics everywhere; do
    "$bin/trainer" eval --aircraft "$name" --data "$out/$d" --json > "$out/$d.eval.json"
  done
  args+=("$name=$out/model.eval.json,$out/aerodynamics.eval.json,$out/everywhere.eval.json")
done
.venv/bin/python "$here/table.py" "${args[@]}"
