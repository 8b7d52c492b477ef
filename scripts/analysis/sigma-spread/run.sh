#!/usr/bin/env bash
# How the estimate's 1σ covers each airframe on its own (docs/results/sigma-spread.md): the
# shipped F-16 estimator's rows (`trainer fit-sigma --rows`) on the 1σ's 25 fitting datasets and on
# the test flights of JSBSim's F-16 and of each development variant, then spread.py: each
# dataset's share within 2σ with every weight of an angle multiplied by one common factor, and the
# factor that brings the fitting dataset farthest from 95 % nearest to it.
#
#   scripts/analysis/sigma-spread/run.sh            # writes out/sigma-spread/
#   scripts/analysis/sigma-spread/run.sh docs/results
#
# Needs the F-16's release build and the flights `scripts/fit-sigma` makes (out/dr, out/dr9,
# out/sigma); the fit it prints goes to out/sigma-spread/*.rs, never into the tree. About 12 min
# on 2 cores (most of it reading the 1.7-GB rows file).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
dest="${1:-out/sigma-spread}"
work=out/sigma-spread
trainer=target/release/trainer
[ -x "$trainer" ] || { echo "sigma-spread: no $trainer: cargo build --release -p trainer first" >&2; exit 2; }
fitting=(--data out/sigma/stock)
for d in dr dr9; do
  for k in 0 1 2 3 4 5 6 7 8 9 10 11; do fitting+=(--data "out/$d/data/$k"); done
done
tests=(--data out/sigma/test/stock)
for t in out/sigma/test/*; do
  [ "$t" = out/sigma/test/stock ] || tests+=(--data "$t")
done
for d in "${fitting[@]}" "${tests[@]}"; do
  [ "$d" = --data ] && continue
  [ -f "$d/manifest.json" ] || { echo "sigma-spread: no $d: run scripts/fit-sigma first (it makes every flight set)" >&2; exit 2; }
done
mkdir -p "$work" "$dest"
if [ ! "$work/fit.csv" -nt "$trainer" ]; then
  "$trainer" fit-sigma "${fitting[@]}" --rows "$work/fit.csv.new" --out "$work/fit.rs" --json > "$work/fit.json"
  mv "$work/fit.csv.new" "$work/fit.csv"
fi
if [ ! "$work/test.csv" -nt "$trainer" ]; then
  "$trainer" fit-sigma "${tests[@]}" --rows "$work/test.csv.new" --out "$work/test.rs" --json > "$work/test.json"
  mv "$work/test.csv.new" "$work/test.csv"
fi
.venv/bin/python scripts/analysis/sigma-spread/spread.py "$work/fit.csv" "$work/test.csv" "$dest"
"$trainer" bars --spec "$work/bars.json" --out "$dest/sigma-spread.png"
echo "wrote $dest/sigma-spread.md and .png" >&2
