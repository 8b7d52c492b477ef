#!/usr/bin/env bash
# Where the shipped estimator's α error near the stall comes from (docs/filter.md, "The 1σ of each
# estimate"): the 32 test flights of the `paper` preset with seeds 11-18 (none trained or fitted
# any shipped estimator; made by scripts/analysis/beta-by-gust/run.sh, or here if missing), each
# flown through the estimator (`hil-sim run --firmware host`), then table.py: the α error by band
# of true α beside the wind's vertical part, which no kinematic input sees.
#
#   scripts/analysis/alpha-wind/run.sh [--aircraft NAME] [--out DIR]
#   scripts/analysis/alpha-wind/run.sh --out docs/results    # the page and its plot
#
# Needs the aircraft's release build (target/ or target/NAME) and the project's .venv
# (scripts/bootstrap). Scratch in out/alpha-wind/NAME/; about 2 min for the F-16 on 2 cores.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh  # default_aircraft, analysis_binaries, paper_test_flights, host_run
command="scripts/analysis/alpha-wind/run.sh${*:+ $*}"
name="$default_aircraft"
dest=""
while [ $# -gt 0 ]; do
  case "$1" in
    --aircraft|--out)
      [ $# -ge 2 ] || { echo "alpha-wind: $1 needs a value (see the header of $0)" >&2; exit 2; }
      if [ "$1" = --aircraft ]; then name="$2"; else dest="$2"; fi
      shift 2 ;;
    *) echo "alpha-wind: unknown argument $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
analysis_binaries "$name" hil-sim trainer
[ -z "$dest" ] || [ -d "$dest" ] || { echo "alpha-wind: --out $dest is not a directory" >&2; exit 2; }
work="out/alpha-wind/$name"
mkdir -p "$work"
paper_test_flights "$name"
for d in "${flight_dirs[@]}"; do
  for csv in "$d"/test_*.csv; do
    flight="$(basename "$csv" .csv)"
    host_run "$work/$(basename "$d")/$flight" "$csv" --aircraft "$name"
  done
  echo "alpha-wind: $d flown" >&2
done
.venv/bin/python scripts/analysis/alpha-wind/table.py "$name" "$work" "$command" "${flight_dirs[@]}"
"$bin/trainer" bars --spec "$work/bars.json" --out "$work/alpha-wind.png"
if [ -n "$dest" ]; then
  mv "$work/alpha-wind.md" "$dest/alpha-wind.md"
  mv "$work/alpha-wind.png" "$dest/alpha-wind.png"
  echo "wrote $dest/alpha-wind.md and .png" >&2
fi
