#!/usr/bin/env bash
# Where an estimate's 1σ is too small: one flight of a dataset replayed through an aircraft's shipped
# estimator (`hil-sim run --firmware host`, as the flight computer answers), then table.py: α and β
# MAE, median 1σ and the share within 2σ by airspeed, flap, α, vertical gust angle and 100-s window
# (docs/results/c172p.md, "The 1σ").
#
#   scripts/analysis/sigma-by-bin/run.sh AIRCRAFT DATASET_CSV
#   scripts/analysis/sigma-by-bin/run.sh c172p out/c172p/test-flight/c172p_test_flight.csv
#
# Needs the aircraft's release build (the default's in target/, another's in target/NAME:
# ESTIMATOR_AIRCRAFT=NAME CARGO_TARGET_DIR=target/NAME cargo build --release -p hil-sim -p trainer)
# and the project's .venv (scripts/bootstrap). Writes out/sigma-by-bin/AIRCRAFT-FLIGHT/; seconds.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
[ $# -eq 2 ] || { echo "usage: scripts/analysis/sigma-by-bin/run.sh AIRCRAFT DATASET_CSV" >&2; exit 2; }
aircraft="$1" csv="$2"
[ -f "$csv" ] || { echo "sigma-by-bin: no $csv (a flight of a dataset: hil-sim generate or fly)" >&2; exit 2; }
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh
aircraft_target "$aircraft"
hil="$target/release/hil-sim"
[ -x "$hil" ] || { echo "sigma-by-bin: no $hil: build the aircraft's release build first (header)" >&2; exit 2; }
out="out/sigma-by-bin/$aircraft-$(basename "$csv" .csv)"
"$hil" run --aircraft "$aircraft" --dataset "$csv" --firmware host --out "$out" > /dev/null
.venv/bin/python scripts/analysis/sigma-by-bin/table.py "$csv" "$out/estimates.csv"
