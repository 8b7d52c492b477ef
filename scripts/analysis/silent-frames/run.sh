#!/usr/bin/env bash
# Where the shipped estimator's silent frames are (docs/results/silent-frames.md): frames with every
# flag clear and α off by more than 2° or β by more than 1°, on flights none of its choices saw:
# the `paper` preset's test cards with seed S flown on JSBSim's F-16 and on each development
# variant (the variants' aircraft directories of scripts/fit-sigma, out/sigma/aircraft/*, made
# there if missing), and on 12 randomised airframes of seed S (`scripts/airframe-randomise --n 12
# --seed S --terms --offset 0.03 --test-only`). Each flight is stepped through the estimator on the
# host (`hil-sim run --firmware host`); table.py sorts the frames by dynamic pressure and by the
# gust angle (the part of α the EGI's velocity and attitude do not give, scripts/analysis/alpha-wind)
# and lists each run of silent frames.
#
#   scripts/analysis/silent-frames/run.sh [--seed S] [--out DIR]
#   scripts/analysis/silent-frames/run.sh --out docs/results    # the page and its plot (seed 26)
#
# Needs the F-16's release build (cargo build --release -p trainer -p hil-sim) and the project's .venv
# (scripts/bootstrap). Scratch in out/silent-frames/S/; about 1.5 min on 2 cores the first time (the
# cards and airframes flown, each flight stepped through the estimator), seconds while the build is
# unchanged (a flight's estimates are kept until hil-sim is rebuilt).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
command="scripts/analysis/silent-frames/run.sh${*:+ $*}"
seed=26
dest=""
while [ $# -gt 0 ]; do
  case "$1" in
    --seed|--out)
      [ $# -ge 2 ] || { echo "silent-frames: $1 needs a value (see the header of $0)" >&2; exit 2; }
      if [ "$1" = --seed ]; then seed="$2"; else dest="$2"; fi
      shift 2 ;;
    *) echo "silent-frames: unknown argument $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
[[ "$seed" =~ ^[0-9]+$ ]] || { echo "silent-frames: --seed $seed is not a whole number" >&2; exit 2; }
[ -z "$dest" ] || [ -d "$dest" ] || { echo "silent-frames: --out $dest is not a directory" >&2; exit 2; }
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh  # default_aircraft, analysis_binaries, host_run, development_cards
analysis_binaries "$default_aircraft" hil-sim trainer
[ -x .venv/bin/python ] || { echo "silent-frames: no .venv: run scripts/bootstrap" >&2; exit 2; }
work="out/silent-frames/$seed"
development_cards "$work/cards" "$seed"
dirs=()
for n in "${card_names[@]}"; do dirs+=("$work/cards/$n"); done
if [ ! -f "$work/airframes/data/11/manifest.json" ]; then
  scripts/airframe-randomise --n 12 --seed "$seed" --terms --offset 0.03 --test-only --out "$work/airframes" --force > /dev/null
fi
for k in $(seq 0 11); do dirs+=("$work/airframes/data/$k"); done
for d in "${dirs[@]}"; do
  for csv in "$d"/test_*.csv; do
    host_run "$work/runs/${d#"$work"/}/$(basename "$csv" .csv)" "$csv"
  done
  echo "silent-frames: $d flown through the estimator" >&2
done
.venv/bin/python scripts/analysis/silent-frames/table.py "$work" "$command" "$seed" "${dirs[@]}"
"$bin/trainer" bars --spec "$work/bars.json" --out "$work/silent-frames.png"
if [ -n "$dest" ]; then
  cp "$work/silent-frames.md" "$work/silent-frames.png" "$dest/"
  echo "silent-frames: wrote $dest/silent-frames.md and .png" >&2
fi
