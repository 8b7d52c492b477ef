#!/usr/bin/env bash
# How firm the calibration table's "gap closed" is (docs/results/gap-spread.md): the table of
# docs/results/calibration.md scores each estimator on the four `paper` test flights of seed 1
# flown on each development variant; this scores the same estimators, as built there, on the
# test flights of more seeds flown on the same variant directories, and prints per seed and
# pooled over every seed the share of the gap between the uncalibrated estimator (the recipe
# trained on JSBSim's F-16) and the matched one (trained on the variant) that the shipped
# estimator closes, int8, α and β. Nothing is trained or fitted here.
#
#   scripts/analysis/gap-spread/run.sh [--seeds 28,29] [--out DIR]
#   scripts/analysis/gap-spread/run.sh --out docs/results    # the page
#
# Needs what scripts/calibration-accuracy leaves in out/calibration (the variants' aircraft
# directories, the reference and matched estimators' f16_tables.rs, weights.rs and sigma.rs, the
# seed-1 test flights), the release build (cargo build --release -p trainer -p hil-sim) and the
# project's .venv (scripts/bootstrap). Each estimator is compiled in with its own tables, weights
# and 1σ into target/aircraft (build-estimator's; seeded from the tree's target/release when missing,
# as build-estimator does), the shipped one is the tree's build. Scratch in out/gap-spread/ (flights
# per seed and variant, flown again when the variant's aircraft is newer); about 5 min on 2 cores,
# most of it the five builds. Seed 7 is refused: build-estimator fits each estimator's 1σ on the
# `paper` flights of seed 7.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
command="scripts/analysis/gap-spread/run.sh${*:+ $*}"
dest=""
seeds="28,29"
while [ $# -gt 0 ]; do
  case "$1" in
    --out)
      [ $# -ge 2 ] || { echo "gap-spread: --out needs a directory (see the header of $0)" >&2; exit 2; }
      dest="$2"; shift 2 ;;
    --seeds)
      [ $# -ge 2 ] || { echo "gap-spread: --seeds needs a comma-separated list of seeds, e.g. 28,29" >&2; exit 2; }
      seeds="$2"; shift 2 ;;
    *) echo "gap-spread: unknown argument $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
[[ "$seeds" =~ ^[0-9]+(,[0-9]+)*$ ]] || { echo "gap-spread: --seeds $seeds: expected seeds like 28,29" >&2; exit 2; }
IFS=, read -r -a given <<< "$seeds"
seed_list=()
declare -A seen
for s in "${given[@]}"; do
  s=$((10#$s))
  [ "$s" != 1 ] || { echo "gap-spread: --seeds: seed 1 is the calibration table's own flights, always scored; give others" >&2; exit 2; }
  [ "$s" != 7 ] || { echo "gap-spread: --seeds: seed 7's paper flights fitted the estimators' 1σ (build-estimator); give others" >&2; exit 2; }
  [ -z "${seen[$s]:-}" ] || { echo "gap-spread: --seeds: seed $s given twice" >&2; exit 2; }
  seen[$s]=1
  seed_list+=("$s")
done
[ -z "$dest" ] || [ -d "$dest" ] || { echo "gap-spread: --out $dest is not a directory" >&2; exit 2; }
for b in trainer hil-sim; do
  [ -x "target/release/$b" ] || { echo "gap-spread: no target/release/$b: run cargo build --release -p trainer -p hil-sim" >&2; exit 2; }
done
[ -x .venv/bin/python ] || { echo "gap-spread: no .venv: run scripts/bootstrap" >&2; exit 2; }
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh  # variant_names, seed_build
variant_names
cal=out/calibration
need=("$cal/reference")
for n in "${variants[@]}"; do need+=("$cal/matched/$n"); done
for d in "${need[@]}"; do
  for f in f16_tables.rs weights.rs sigma.rs; do
    [ -f "$d/$f" ] || { echo "gap-spread: no $d/$f: run scripts/calibration-accuracy first (it builds the estimators scored here)" >&2; exit 2; }
  done
done
for n in "${variants[@]}"; do
  [ -f "$cal/test/$n/manifest.json" ] && [ -f "$cal/aircraft/$n/f16/f16.xml" ] ||
    { echo "gap-spread: $cal lacks $n's aircraft or test flights: run scripts/calibration-accuracy first" >&2; exit 2; }
done
work=out/gap-spread
mkdir -p "$work/eval"
# The flights: seed 1 is the table's own; every other seed flown on the same aircraft directory.
declare -A flights
for n in "${variants[@]}"; do
  flights["1/$n"]="$cal/test/$n"
  for s in "${seed_list[@]}"; do
    d="$work/$s/$n"
    if [ ! "$d/manifest.json" -nt "$cal/aircraft/$n/f16/f16.xml" ]; then
      echo "gap-spread: flying seed $s on $n" >&2
      rm -rf "$d"
      target/release/hil-sim generate --preset paper --test-only --seed "$s" --aircraft-dir "$cal/aircraft/$n" --out "$d" > /dev/null
    fi
    flights["$s/$n"]="$d"
  done
done
all_seeds=(1 "${seed_list[@]}")
score() {  # score EST TRAINER VARIANT...: every seed's test flights of each variant
  local est="$1" bin="$2" n s
  shift 2
  for n in "$@"; do
    for s in "${all_seeds[@]}"; do
      "$bin" eval --data "${flights["$s/$n"]}" --json > "$work/eval/$est-$s-$n.json.partial"
      mv "$work/eval/$est-$s-$n.json.partial" "$work/eval/$est-$s-$n.json"
    done
  done
}
est_target=target/aircraft
(target="$root/$est_target"; seed_build release)
build_with() {  # build_with DIR: the trainer with DIR's tables, weights and 1σ compiled in
  echo "gap-spread: building the estimator of $1" >&2
  ESTIMATOR_AIRCRAFT=f16 ESTIMATOR_AERO="$root/$1/f16_tables.rs" ESTIMATOR_WEIGHTS="$root/$1/weights.rs" ESTIMATOR_SIGMA="$root/$1/sigma.rs" \
    CARGO_TARGET_DIR="$est_target" cargo build --release -q -p trainer
}
score shipped target/release/trainer "${variants[@]}"
build_with "$cal/reference"
score uncalibrated "$est_target/release/trainer" "${variants[@]}"
for n in "${variants[@]}"; do
  build_with "$cal/matched/$n"
  score matched "$est_target/release/trainer" "$n"
done
.venv/bin/python scripts/analysis/gap-spread/table.py "$work" "$command" "${all_seeds[*]}" "${variants[@]}" > "$work/gap-spread.md"
target/release/trainer bars --spec "$work/bars.json" --out "$work/gap-spread.png"
if [ -n "$dest" ]; then
  cp "$work/gap-spread.md" "$work/gap-spread.png" "$dest/"
  echo "gap-spread: wrote $dest/gap-spread.md and .png" >&2
else
  cat "$work/gap-spread.md"
fi
