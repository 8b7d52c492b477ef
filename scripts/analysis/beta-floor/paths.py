"""Where the β-floor analysis reads and writes (standard library only, so the shell steps can use it).

REPO  the repository root, from this file's location (scripts/analysis/beta-floor → ../../..)
DATA  the dataset (hil-sim generate --preset large --seed 1): env DATA, default <repo>/out/data/large
WORK  every output and work directory (run-<flight>/, replay/, cf/, filter/, cache/, out/, bin/):
      env WORK, default <repo>/out/beta-floor
"""
import os

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
DATA = os.path.abspath(os.environ.get("DATA") or os.path.join(REPO, "out", "data", "large"))
WORK = os.path.abspath(os.environ.get("WORK") or os.path.join(REPO, "out", "beta-floor"))
VAL_FLIGHTS = os.path.join(HERE, "val_flights.txt")  # the trainer's 10 validation flights (checked in)
