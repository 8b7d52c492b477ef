#!/bin/sh
# The shipped estimator (compiled into hil-sim, host firmware, clean default link: no loss, no flips)
# on every flight of $DATA; one directory per flight: $WORK/run-<flight>/estimates.csv (+ .json, .err).
# Computes the per-frame β̂ every analysis script reads.
set -e
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/env.sh"
mkdir -p "$WORK"
cd "$REPO"
for csv in "$DATA"/*.csv; do
  name=$(basename "$csv" .csv)
  nice -n 19 "$HIL_SIM" run --dataset "$csv" --firmware host --json \
    --out "$WORK/run-$name" > "$WORK/run-$name.json" 2>"$WORK/run-$name.err"
done
