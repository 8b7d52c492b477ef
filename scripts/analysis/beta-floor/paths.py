"""Where the β-floor analysis reads and writes (standard library only, so the shell steps can use it).

REPO      the repository root, from this file's location (scripts/analysis/beta-floor → ../../..)
AIRCRAFT  the aircraft of $DATA (aircraft/<name>.toml: its JSBSim model, wing area, IMU lever arm):
          env AIRCRAFT, default f16. Only the replay and the sensor floors (replay120, k_floor120,
          i_sensor_floor's part 1) are aircraft-generic; the other scripts read the F-16's tables.
DATA      the dataset (hil-sim generate --preset large --seed 1): env DATA, default
          <repo>/out/data/large (the F-16), <repo>/out/<aircraft>/large for another aircraft
WORK      every output and work directory (run-<flight>/, replay/, cf/, filter/, cache/, out/, bin/):
          env WORK, default <repo>/out/beta-floor (the F-16), <repo>/out/beta-floor-<aircraft> otherwise
"""
import os

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
AIRCRAFT = os.environ.get("AIRCRAFT") or "f16"
_F16 = AIRCRAFT == "f16"
DATA = os.path.abspath(os.environ.get("DATA") or (os.path.join(REPO, "out", "data", "large") if _F16
                                                  else os.path.join(REPO, "out", AIRCRAFT, "large")))
WORK = os.path.abspath(os.environ.get("WORK") or os.path.join(REPO, "out", "beta-floor" if _F16 else "beta-floor-" + AIRCRAFT))
VAL_FLIGHTS = os.path.join(HERE, "val_flights.txt")  # the trainer's 10 validation flights (checked in)
