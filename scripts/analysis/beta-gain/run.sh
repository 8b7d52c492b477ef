#!/usr/bin/env bash
# Whether the shipped β is off by a gain on an airframe whose side force is not the model's
# (docs/results/beta-gain.md): the F-16's test flights that scripts/fit-sigma flies on JSBSim's
# model and on each development variant (out/sigma/test/*, made there if missing), stepped by the
# shipped estimator (`trainer fit-sigma --rows`: every frame's β error) and by its air-data filter
# alone (`trainer eval-filter`: the side-force scale it learned); then table.py: per aircraft and
# flight, the slope of the β error over the true β (a gain error of -0.1 reads 10 % low), the MAE
# and the share of frames within the reported 2σ as flown and with that gain taken out, and the filter's
# side-force scale at the end of the flight, beside the variant's own side-force change
# (airframes/f16-variants/NAME.toml).
#
#   scripts/analysis/beta-gain/run.sh [--out DIR]
#   scripts/analysis/beta-gain/run.sh --out docs/results    # the page
#
# Needs the release build (cargo build --release -p trainer -p hil-sim) and the project's .venv
# (scripts/bootstrap). Scratch in out/beta-gain/; about 20 s on 2 cores.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
command="scripts/analysis/beta-gain/run.sh${*:+ $*}"
dest=""
while [ $# -gt 0 ]; do
  case "$1" in
    --out)
      [ $# -ge 2 ] || { echo "beta-gain: --out needs a directory (see the header of $0)" >&2; exit 2; }
      dest="$2"; shift 2 ;;
    *) echo "beta-gain: unknown argument $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
[ -z "$dest" ] || [ -d "$dest" ] || { echo "beta-gain: --out $dest is not a directory" >&2; exit 2; }
trainer=target/release/trainer
[ -x "$trainer" ] || { echo "beta-gain: no $trainer: run cargo build --release -p trainer -p hil-sim" >&2; exit 2; }
[ -x .venv/bin/python ] || { echo "beta-gain: no .venv: run scripts/bootstrap" >&2; exit 2; }
# shellcheck source=../../lib/aircraft.sh
. scripts/lib/aircraft.sh  # development_variants
development_variants
names=(stock "${variants[@]}")
work=out/beta-gain
mkdir -p "$work"
data=()
for n in "${names[@]}"; do
  data+=(--data "out/sigma/test/$n")
  "$trainer" eval-filter --data "out/sigma/test/$n" --json > "$work/filter-$n.json"
done
# The fit this prints is thrown away (its sigma.rs goes to the scratch); the rows carry the
# shipped estimator's β and its error on every frame.
"$trainer" fit-sigma "${data[@]}" --every 1 --out "$work/unused-sigma.rs" --rows "$work/rows.csv" > "$work/fit.log"
.venv/bin/python scripts/analysis/beta-gain/table.py "$work" "$command" "${names[@]}" > "$work/beta-gain.md"
"$trainer" bars --spec "$work/bars.json" --out "$work/beta-gain.png"
if [ -n "$dest" ]; then
  cp "$work/beta-gain.md" "$work/beta-gain.png" "$dest/"
  echo "beta-gain: wrote $dest/beta-gain.md and .png" >&2
else
  cat "$work/beta-gain.md"
fi
