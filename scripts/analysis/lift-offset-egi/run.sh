#!/usr/bin/env bash
# Where the flight-test identification's lift offset ΔC_L errs on the aircraft's own model
# (docs/calibration.md, "Flight-test accuracy"): the `flight-test` card flown on JSBSim's model on
# sensor seeds 1 and 10-13 (the flight tests) and 2-9 (the model cards), each identified by
# `trainer calibrate` over the eight cards as recorded, and again with every dataset's EGI attitude
# and ground velocity replaced by the simulator's truth (truth_egi.py: a diagnostic, never a
# calibration input). The truth of ΔC_L is 0 and of the lift scale 1; table.py prints both fits.
#
#   scripts/analysis/lift-offset-egi/run.sh [AIRCRAFT]   # default f16
#
# Needs the aircraft's release build (the F-16's in target/, another's in target/NAME:
# ESTIMATOR_AIRCRAFT=NAME CARGO_TARGET_DIR=target/NAME cargo build --release -p hil-sim -p trainer)
# and the project's .venv (scripts/bootstrap). Writes out/lift-offset-egi/AIRCRAFT/ (flights kept,
# 1.7 GB for the F-16); about 10 min on 2 cores from an empty directory.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh  # default_aircraft, analysis_binaries
usage() { echo "usage: scripts/analysis/lift-offset-egi/run.sh [AIRCRAFT]" >&2; exit 2; }
case "${1:-}" in
  -h|--help) awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "$root/scripts/analysis/lift-offset-egi/run.sh"; exit 0 ;;
  -*) echo "lift-offset-egi: unknown option $1" >&2; usage ;;
esac
[ $# -le 1 ] || { echo "lift-offset-egi: one AIRCRAFT at most (given: $*)" >&2; usage; }
name="${1:-$default_aircraft}"
analysis_binaries "$name" hil-sim trainer
[ -x .venv/bin/python ] || { echo "lift-offset-egi: no .venv: run scripts/bootstrap" >&2; exit 2; }
here=scripts/analysis/lift-offset-egi
out="out/lift-offset-egi/$name"
export HIL_PYTHON="${HIL_PYTHON:-$root/.venv/bin/python}"
tests=(1 10 11 12 13)
cards=(2 3 4 5 6 7 8 9)
for s in "${tests[@]}" "${cards[@]}"; do
  d="$out/recorded/seed-$s"
  if [ ! -f "$d/manifest.json" ]; then
    "$bin/hil-sim" generate --aircraft "$name" --preset flight-test --seed "$s" --out "$d" --force > /dev/null
  fi
  [ -f "$out/truth-egi/seed-$s/manifest.json" ] || .venv/bin/python "$here/truth_egi.py" "$d" "$out/truth-egi/seed-$s"
done
args=()
for mode in recorded truth-egi; do
  card_args=()
  for c in "${cards[@]}"; do card_args+=(--model-flight-test "$out/$mode/seed-$c"); done
  for s in "${tests[@]}"; do
    "$bin/trainer" calibrate --aircraft "$name" --flight-test "$out/$mode/seed-$s" "${card_args[@]}" \
      --out "$out/ident-$mode-$s" > /dev/null
    args+=("$mode/$s=$out/ident-$mode-$s/calibration.json")
  done
done
.venv/bin/python "$here/table.py" "${args[@]}"
