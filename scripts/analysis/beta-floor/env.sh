# Sourced by the shell steps of the β-floor analysis (after setting HERE to this directory).
# The shell twin of paths.py: same defaults, every path made absolute before any step changes directory.
#   AIRCRAFT the aircraft of DATA (aircraft/<name>.toml)                   default f16
#   DATA     the dataset (hil-sim generate --preset large --seed 1)   default <repo>/out/data/large
#                                                  (another aircraft: <repo>/out/<aircraft>/large)
#   WORK     every output and work dir (run-*, replay/, cf/, filter/, cache/, out/, bin/)
#                                                                     default <repo>/out/beta-floor
#                                                  (another aircraft: <repo>/out/beta-floor-<aircraft>)
#   HIL_SIM  TRAINER   the binaries      default <repo>/target/release/hil-sim, <repo>/target/release/trainer
#                      (another aircraft: its own build, <repo>/target/<aircraft>/release/..., scripts/lib/aircraft.sh)
#   PY       the Python interpreter      default <repo>/.venv/bin/python (scripts/bootstrap makes it)
REPO=$(cd "$HERE/../../.." && pwd)
abs_path() { case $1 in /*) printf '%s' "$1" ;; *) printf '%s' "$PWD/$1" ;; esac; }
AIRCRAFT=${AIRCRAFT:-f16}
if [ "$AIRCRAFT" = f16 ]; then
  DATA=$(abs_path "${DATA:-$REPO/out/data/large}")
  WORK=$(abs_path "${WORK:-$REPO/out/beta-floor}")
  TARGET="$REPO/target"
else
  DATA=$(abs_path "${DATA:-$REPO/out/$AIRCRAFT/large}")
  WORK=$(abs_path "${WORK:-$REPO/out/beta-floor-$AIRCRAFT}")
  TARGET="$REPO/target/$AIRCRAFT"
fi
HIL_SIM=$(abs_path "${HIL_SIM:-$TARGET/release/hil-sim}")
TRAINER=$(abs_path "${TRAINER:-$TARGET/release/trainer}")
PY=$(abs_path "${PY:-$REPO/.venv/bin/python}")
export AIRCRAFT DATA WORK HIL_SIM TRAINER PY
