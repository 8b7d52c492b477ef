#!/usr/bin/env bash
# The side force's identification over the model cards and over the second card (the same
# `flight-test` card flown on the first calibrated aircraft; docs/calibration.md, Method step 5),
# against the truth, on the F-16's development variants (airframes/f16-variants/) and on the
# airframes `scripts/airframe-randomise --n 3 --seed S --terms --offset 0.03` draws for each seed
# given (default 31 32). Each airframe's flight test is flown with sensor seed 1, the model cards
# and the second cards with seeds 2-9, and `trainer calibrate` identifies as `scripts/calibrate`'s
# step 1 does (no estimator is built). table.py prints k_β and k_Y both ways beside the truth
# (k_β: SIDE × CYb; k_Y against the rudder's, the aileron's and the rate terms' scales) and writes
# the bars of their errors.
#
#   scripts/analysis/side-force-card/run.sh [--out DIR] [SEED...]
#
# --out DIR copies side-force-card.md and .png there (docs/results for the committed page).
# Needs the F-16's release build (cargo build --release -p hil-sim -p trainer) and the project's
# .venv (scripts/bootstrap). Writes out/side-force-card/ (flights kept, about 7 GB for ten
# airframes); about 25 min on 2 cores from an empty directory. Every step resumes: delete
# out/side-force-card after changing the trainer or an airframe's spec.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh  # analysis_binaries
usage() { echo "usage: scripts/analysis/side-force-card/run.sh [--out DIR] [SEED...]" >&2; exit 2; }
dest="" seeds=()
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "$root/scripts/analysis/side-force-card/run.sh"; exit 0 ;;
    --out) [ $# -ge 2 ] && [ -d "$2" ] || { echo "side-force-card: --out needs an existing directory" >&2; usage; }
      dest="$2"; shift 2 ;;
    -*) echo "side-force-card: unknown option $1" >&2; usage ;;
    *) [[ "$1" =~ ^[0-9]+$ ]] || { echo "side-force-card: seed $1: a number" >&2; usage; }
      seeds+=("$1"); shift ;;
  esac
done
[ ${#seeds[@]} -gt 0 ] || seeds=(31 32)
analysis_binaries f16 hil-sim trainer
[ -x .venv/bin/python ] || { echo "side-force-card: no .venv: run scripts/bootstrap" >&2; exit 2; }
export HIL_PYTHON="${HIL_PYTHON:-$root/.venv/bin/python}"
out=out/side-force-card
mkdir -p "$out"
cards=(2 3 4 5 6 7 8 9)
# fly DIR ARGS...: a flight-test card into DIR unless it is there.
fly() {
  local d="$1"
  shift
  [ -f "$d/manifest.json" ] || "$bin/hil-sim" generate --preset flight-test "$@" --out "$d" --force > /dev/null
}
# The airframes: NAME=SPEC, their aircraft directories made from the specs.
airframes=()
for spec in airframes/f16-variants/*.toml; do
  airframes+=("$(basename "$spec" .toml)=$spec")
done
for s in "${seeds[@]}"; do
  [ -f "$out/dr$s/variants.json" ] ||
    scripts/airframe-randomise --n 3 --seed "$s" --terms --offset 0.03 --test-only --out "$out/dr$s" --force > /dev/null
  for k in 0 1 2; do airframes+=("random-$s-$k=$out/dr$s/specs/$k.toml"); done
done
model_args=()
for c in "${cards[@]}"; do
  fly "$out/card-$c" --seed "$c"
  model_args+=(--model-flight-test "$out/card-$c")
done
args=()
for a in "${airframes[@]}"; do
  n="${a%%=*}" spec="${a#*=}"
  echo "side-force-card: $n" >&2
  [ -f "$out/aircraft/$n/f16/f16.xml" ] ||
    scripts/airframe-variant "$spec" --model f16 --out "$out/aircraft/$n" --force > /dev/null
  fly "$out/ft/$n" --seed 1 --aircraft-dir "$out/aircraft/$n"
  [ -f "$out/first/$n/calibration.json" ] ||
    "$bin/trainer" calibrate --flight-test "$out/ft/$n" "${model_args[@]}" --out "$out/first/$n" > /dev/null
  [ -f "$out/first/$n/aircraft/f16/f16.xml" ] ||
    scripts/airframe-variant "$out/first/$n/aircraft.toml" --model f16 --out "$out/first/$n/aircraft" --force > /dev/null
  second_args=()
  for c in "${cards[@]}"; do
    fly "$out/second/$n-$c" --seed "$c" --aircraft-dir "$out/first/$n/aircraft"
    second_args+=(--moment-flight-test "$out/second/$n-$c")
  done
  [ -f "$out/final/$n/calibration.json" ] ||
    "$bin/trainer" calibrate --flight-test "$out/ft/$n" "${model_args[@]}" "${second_args[@]}" \
      --first-calibration "$out/first/$n/calibration.json" --out "$out/final/$n" > /dev/null
  args+=("$n=$spec")
done
command="scripts/analysis/side-force-card/run.sh${seeds:+ ${seeds[*]}}"
.venv/bin/python scripts/analysis/side-force-card/table.py "$out" "$command" "${args[@]}" > "$out/side-force-card.md"
"$bin/trainer" bars --spec "$out/bars.json" --out "$out/side-force-card.png"
if [ -n "$dest" ]; then
  cp "$out/side-force-card.md" "$out/side-force-card.png" "$dest/"
  echo "side-force-card: wrote $dest/side-force-card.md and .png" >&2
else
  cat "$out/side-force-card.md"
fi
