#!/bin/sh
# The model-based filter alone on the TRAINING split (never test) with one constant changed at a
# time: trainer eval-filter --split train --tune KEY=V --json. One JSON per variant in $WORK/filter/
# (summarised by filter_summary.py).
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/env.sh"
mkdir -p "$WORK/filter"
cd "$REPO"
for t in "" gust_sigma=1 gust_sigma=4 gust_sigma=6 gust_tau_s=0.3 gust_tau_s=3 accel_sigma_y=0.4 accel_sigma_y=1.6 accel_delay_s=0.02 accel_delay_s=0.04 "gust_sigma=4,accel_sigma_y=0.4"; do
  name=$(echo "base$t" | tr '=,' '__')
  nice -n 19 "$TRAINER" eval-filter --data "$DATA" --split train --tune "$t" --json > "$WORK/filter/$name.json" 2> "$WORK/filter/$name.err"
  echo "$name rc=$?"
done
