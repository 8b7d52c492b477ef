# Sourced by the shell steps of the β-floor analysis (after setting HERE to this directory).
# The shell twin of paths.py: same defaults, every path made absolute before any step changes directory.
#   DATA     the dataset (hil-sim generate --preset large --seed 1)   default <repo>/out/data/large
#   WORK     every output and work dir (run-*, replay/, cf/, filter/, cache/, out/, bin/)
#                                                                     default <repo>/out/beta-floor
#   HIL_SIM  TRAINER   the binaries      default <repo>/target/release/hil-sim, <repo>/target/release/trainer
#   PY       the Python interpreter      default <repo>/.venv/bin/python (scripts/bootstrap makes it)
REPO=$(cd "$HERE/../../.." && pwd)
abs_path() { case $1 in /*) printf '%s' "$1" ;; *) printf '%s' "$PWD/$1" ;; esac; }
DATA=$(abs_path "${DATA:-$REPO/out/data/large}")
WORK=$(abs_path "${WORK:-$REPO/out/beta-floor}")
HIL_SIM=$(abs_path "${HIL_SIM:-$REPO/target/release/hil-sim}")
TRAINER=$(abs_path "${TRAINER:-$REPO/target/release/trainer}")
PY=$(abs_path "${PY:-$REPO/.venv/bin/python}")
export DATA WORK HIL_SIM TRAINER PY
