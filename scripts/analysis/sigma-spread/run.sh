#!/usr/bin/env bash
# How the estimate's 1σ covers each airframe on its own (docs/results/sigma-spread.md, and
# docs/results/NAME/sigma-spread.md for another aircraft): a shipped estimator's rows
# (`trainer fit-sigma --rows`) on the datasets its committed 1σ was fitted on (the `--data` of the
# `command:` in estimator-core/src/model/NAME/sigma.rs) and on test flights, then spread.py: each
# dataset's share within 2σ with every weight of an angle multiplied by one common factor, and the
# factor that brings the fitting dataset farthest from 95 % nearest to it.
#
#   scripts/analysis/sigma-spread/run.sh [--aircraft NAME] [--out DIR] [TEST_DATASET ...]
#   scripts/analysis/sigma-spread/run.sh --out docs/results        # the F-16: out/sigma/test/*
#   scripts/analysis/sigma-spread/run.sh --aircraft c172p --out docs/results/c172p out/calibration-c172p/test/*
#
# TEST_DATASET: default, for the F-16, the test flights `scripts/fit-sigma` flies on JSBSim's model
# (out/sigma/test/stock) and on each development variant; a dataset named `stock` is the model's.
# Needs the aircraft's release build (target/ or target/NAME) and the fitting datasets its sigma.rs
# names (scripts/fit-sigma makes the F-16's). The fit it prints goes to out/sigma-spread/NAME/, never
# into the tree. About 12 min for the F-16 on 2 cores (most of it reading the 1.7-GB rows file).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh  # default_aircraft, aircraft_target
command="scripts/analysis/sigma-spread/run.sh${*:+ $*}"
name="$default_aircraft"
dest=""
tests=()
while [ $# -gt 0 ]; do
  case "$1" in
    --aircraft|--out)
      [ $# -ge 2 ] || { echo "sigma-spread: $1 needs a value (see the header of $0)" >&2; exit 2; }
      if [ "$1" = --aircraft ]; then name="$2"; else dest="$2"; fi
      shift 2 ;;
    -*) echo "sigma-spread: unknown option $1 (see the header of $0)" >&2; exit 2 ;;
    *) tests+=("$1"); shift ;;
  esac
done
aircraft_target "$name"
trainer="$target/release/trainer"
if [ ! -x "$trainer" ]; then
  if [ "$name" = "$default_aircraft" ]; then build="cargo build --release -p trainer"
  else build="ESTIMATOR_AIRCRAFT=$name CARGO_TARGET_DIR=target/$name cargo build --release -p trainer"; fi
  echo "sigma-spread: no $trainer: build it first ($build)" >&2
  exit 2
fi
sigma="estimator-core/src/model/$name/sigma.rs"
[ -f "$sigma" ] || { echo "sigma-spread: no $sigma: $name has no 1σ fit" >&2; exit 2; }
mapfile -t fitting < <(grep -o 'SIGMA_PROVENANCE: &str = "command: [^\\]*' "$sigma" | grep -o -- '--data [^ ]*' | cut -d' ' -f2)
[ ${#fitting[@]} -gt 0 ] || { echo "sigma-spread: $sigma names no --data in its command" >&2; exit 2; }
if [ ${#tests[@]} -eq 0 ]; then
  [ "$name" = "$default_aircraft" ] || { echo "sigma-spread: name $name's test datasets (e.g. out/calibration-$name/test/*)" >&2; exit 2; }
  tests=(out/sigma/test/stock)
  for t in out/sigma/test/*/; do
    t="${t%/}"
    [ "$t" = out/sigma/test/stock ] || tests+=("$t")
  done
fi
[ -x .venv/bin/python ] || { echo "sigma-spread: no .venv/bin/python: run scripts/bootstrap first" >&2; exit 2; }
for d in "${fitting[@]}" "${tests[@]}"; do
  [ -f "$d/manifest.json" ] || { echo "sigma-spread: no dataset $d (the F-16's: scripts/fit-sigma makes every one; another aircraft's: the commands of docs/results/$name.md)" >&2; exit 2; }
done
work="out/sigma-spread/$name"
dest="${dest:-$work}"
mkdir -p "$work" "$dest"
rows() {  # rows OUT DATASET...: the rows file, redone when the trainer or a dataset is newer or
  # the datasets asked for are not those it was made of ($work/OUT.data)
  local out="$1" data=() d fresh=1
  shift
  [ "$work/$out.csv" -nt "$trainer" ] || fresh=0
  for d in "$@"; do
    data+=(--data "$d")
    [ "$work/$out.csv" -nt "$d/manifest.json" ] || fresh=0
  done
  [ "$(cat "$work/$out.data" 2>/dev/null)" = "$(printf '%s\n' "$@")" ] || fresh=0
  if [ "$fresh" = 0 ]; then
    "$trainer" fit-sigma --aircraft "$name" "${data[@]}" --rows "$work/$out.csv.new" \
      --out "$work/$out.rs" --json > "$work/$out.json"
    mv "$work/$out.csv.new" "$work/$out.csv"
    printf '%s\n' "$@" > "$work/$out.data"
  fi
}
rows fit "${fitting[@]}"
rows test "${tests[@]}"
# The page and its plot are made in the scratch directory and moved together.
.venv/bin/python scripts/analysis/sigma-spread/spread.py "$name" "$work/fit.csv" "$work/test.csv" \
  "$work/sigma-spread.md" "$work/bars.json" "$command"
"$trainer" bars --spec "$work/bars.json" --out "$work/sigma-spread.png"
if ! [ "$dest" -ef "$work" ]; then
  mv "$work/sigma-spread.png" "$dest/sigma-spread.png"
  mv "$work/sigma-spread.md" "$dest/sigma-spread.md"
fi
echo "wrote $dest/sigma-spread.md and .png" >&2
