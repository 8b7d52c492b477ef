#!/usr/bin/env bash
# The whole β-floor analysis (docs/results/beta-floor.md) in its original order:
#   data       hil-sim generate --preset large --seed 1 into $DATA, if $DATA has no manifest.json
#   estimates  run_all.sh: the shipped hybrid on all 68 flights → $WORK/run-<flight>/
#   replay     replay120.py: 120 Hz JSBSim internals of the 4 test + the aggressive training flights
#              (16 in `large`, 4 in `paper`)
#   tables     a_where … j_matched, k_floor120 → $WORK/out/*.md
#   floors     i_sensor_floor, k_floor120 only (the sensor floors: no estimates needed) → $WORK/out/
#   cf         cf_run.sh, cf_run2.sh: counterfactual re-flights (severity, EGI, anti-alias) → $WORK/cf/
#   filter     filter_tune.sh + filter_summary.py: the filter alone on the training split
# usage: scripts/analysis/beta-floor/run.sh [step ...]      (no step: all, in the order above)
#        AIRCRAFT=f15 DATA=out/f15/paper scripts/analysis/beta-floor/run.sh replay floors
# Environment (see env.sh): AIRCRAFT, DATA, WORK, HIL_SIM, TRAINER, PY; COPY_BINS=1 first copies hil-sim
# and trainer to $WORK/bin and uses the copies, so a rebuild in target/ cannot change them mid-run.
# AIRCRAFT (default f16) names the aircraft of DATA (aircraft/<name>.toml); on another aircraft than the
# F-16 only the steps data (with that aircraft's build), replay and floors apply (floors: i_sensor_floor
# part 1 and k_floor120; the other tables read the F-16's tables).
# Needs release builds of hil-sim and trainer from the same checkout (this script does not build)
# and the project's .venv (scripts/bootstrap: jsbsim, which brings numpy; nothing else is needed).
# The figures in docs/results/beta-floor.md were measured at git 04512c2, whose dataset had point-
# sampled surfaces; on a later checkout the same commands measure the current sensor model.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
. "$HERE/env.sh"
say() { printf '\n--> %s\n' "$*" >&2; }
die() { printf 'beta-floor: ERROR: %s\n' "$*" >&2; exit 1; }

usage() { echo "usage: scripts/analysis/beta-floor/run.sh [data|estimates|replay|tables|floors|cf|filter ...]" >&2; exit 2; }

# Everything is checked before anything is written: a refused run leaves no $WORK behind.
steps=("$@")
case "${1:-}" in
  -h|--help) awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "$HERE/run.sh"; exit 0 ;;
esac
if [ ! -f "$REPO/aircraft/$AIRCRAFT.toml" ]; then
  known="$(cd "$REPO/aircraft" && ls -- *.toml | sed 's/\.toml$//' | paste -sd' ' -)"
  echo "beta-floor: AIRCRAFT=$AIRCRAFT: no aircraft/$AIRCRAFT.toml (described: $known; docs/aircraft.md)" >&2
  exit 2
fi
[ ${#steps[@]} -gt 0 ] || steps=(data estimates replay tables cf filter)
for s in "${steps[@]}"; do
  case "$s" in data|estimates|replay|tables|floors|cf|filter) ;; *) echo "beta-floor: unknown step '$s'" >&2; usage ;; esac
  case "$AIRCRAFT:$s" in f16:*|*:data|*:replay|*:floors) ;; *) die "step '$s' is the F-16's only (AIRCRAFT=$AIRCRAFT)" ;; esac
done
want() { local s; for s in "${steps[@]}"; do [ "$s" = "$1" ] && return 0; done; return 1; }

[ -x "$PY" ] || die "no Python at $PY; run scripts/bootstrap (or set PY)"
if want data || want estimates || want cf; then
  [ -x "$HIL_SIM" ] || die "no hil-sim at $HIL_SIM; cargo build --release -p hil-sim (or set HIL_SIM)"
fi
if want filter; then
  [ -x "$TRAINER" ] || die "no trainer at $TRAINER; cargo build --release -p trainer (or set TRAINER)"
fi
if [ "${COPY_BINS:-0}" = 1 ]; then
  [ -x "$HIL_SIM" ] && [ -x "$TRAINER" ] ||
    die "COPY_BINS=1 copies both $HIL_SIM and $TRAINER; cargo build --release -p hil-sim -p trainer (or set HIL_SIM, TRAINER)"
fi
if ! want data; then
  [ -f "$DATA/manifest.json" ] || die "no dataset at $DATA (run the 'data' step or set DATA)"
fi
mkdir -p "$WORK/out"
if [ "${COPY_BINS:-0}" = 1 ]; then
  mkdir -p "$WORK/bin"
  cp -p "$HIL_SIM" "$TRAINER" "$WORK/bin/"
  HIL_SIM="$WORK/bin/hil-sim"; TRAINER="$WORK/bin/trainer"
  export HIL_SIM TRAINER
fi
say "AIRCRAFT=$AIRCRAFT  DATA=$DATA  WORK=$WORK  HIL_SIM=$HIL_SIM  PY=$PY"

if want data; then
  if [ -f "$DATA/manifest.json" ]; then
    say "data: $DATA exists, kept"
  else
    say "data: hil-sim generate --preset large --seed 1 --out $DATA"
    (cd "$REPO" && nice -n 19 "$HIL_SIM" generate --preset large --seed 1 --out "$DATA")
  fi
fi
[ -f "$DATA/manifest.json" ] || die "no dataset at $DATA (run the 'data' step or set DATA)"

if want estimates; then
  say "estimates: the shipped estimator on every flight → $WORK/run-*"
  "$HERE/run_all.sh"
fi

if want replay; then
  say "replay: 120 Hz JSBSim internals → $WORK/replay"
  # shellcheck disable=SC2046  # the training flights' names, one word each
  nice -n 19 "$PY" "$HERE/replay120.py" test_gentle_00 test_high-alpha_01 test_climb-descent_02 test_aggressive_03 \
    $(cd "$HERE" && "$PY" -c 'import common; print(*(f["name"] for f in common.flights("train") if f["profile"] == "aggressive"))')
fi

if want tables; then
  for t in a_where b_timescale c_physics d_turb f_floor g_by_flight h_residual i_sensor_floor j_matched k_floor120; do
    say "tables: $t.py → $WORK/out/$t.md"
    nice -n 19 "$PY" "$HERE/$t.py" > "$WORK/out/$t.md"
  done
fi

if want floors; then
  for t in i_sensor_floor k_floor120; do
    say "floors: $t.py → $WORK/out/$t.md"
    nice -n 19 "$PY" "$HERE/$t.py" > "$WORK/out/$t.md"
  done
fi

if want cf; then
  say "cf: counterfactual re-flights → $WORK/cf (summary: $WORK/out/cf_run.log)"
  { "$HERE/cf_run.sh"; "$HERE/cf_run2.sh"; } | tee "$WORK/out/cf_run.log"
fi

if want filter; then
  say "filter: trainer eval-filter --split train, one constant at a time → $WORK/filter"
  "$HERE/filter_tune.sh"
  "$PY" "$HERE/filter_summary.py" > "$WORK/out/filter_tune.md"
fi
say "done: tables in $WORK/out"
