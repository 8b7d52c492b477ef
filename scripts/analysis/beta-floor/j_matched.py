"""What if the surface position sensors had the IMU's anti-alias filter (matched timing)?

The accelerometer sees the side force of the rudder through the 6 Hz anti-alias filter, the rudder
channel is an instantaneous 20 Hz sample of a rudder that (in this plant) jumps ±30° at 120 Hz.
Here the Ay inversion is done (i) with the sampled surfaces 30 ms back (as now, S1) and (ii) with the
surfaces passed through the same lag + Butterworth as the IMU (M1). Each is then combined causally
and linearly (lags 0..5) with the EGI kinematic β (non-turbulent wind exact) — fitted on the 16
aggressive training flights, scored on the test flights.

Needs: $WORK/run-<flight>/ and $WORK/replay/ of the test and the 16 aggressive training flights.
usage: nice -n 19 <repo>/.venv/bin/python j_matched.py > "$WORK/out/j_matched.md"
"""
import numpy as np

from c_physics import R, delayed, invert
from common import FT, flights, imu_filter_120, mae
from d_turb import egi_beta, parts
from f_floor import TESTS, lags
from frames import table


def prep(n):
    d = table(n)
    r = d["r120"]
    i = d["idx120"]
    b_all, b_nt = parts(d)
    w_nt = (np.array([r["atmosphere__total_wind_north_fps"], r["atmosphere__total_wind_east_fps"], r["atmosphere__total_wind_down_fps"]])
            - np.array([r["atmosphere__turb_north_fps"], r["atmosphere__turb_east_fps"], r["atmosphere__turb_down_fps"]]))[:, i] * FT
    b_nt_egi = egi_beta(d, w_nt)
    base = dict(qbar=d["qbar_pa"], mass=d["mass_kg"], alpha=R(d["alpha_deg"]), mach=d["mach"], tas=d["vt_mps"])
    s1 = invert(d, **base, surf_delay=0.03)
    f = lambda k: imu_filter_120(r[k])[i]
    surf_m = (f("fcs__aileron_pos_rad"), f("fcs__rudder_pos_rad"), f("fcs__elevator_pos_rad"),
              delayed(R(d["speedbrake_deg"]), 0.03), delayed(1.4324 * (2 * d["flaperon_deg"] + 2 * d["tef_deg"]) / 20.0, 0.03))
    m1 = invert(d, **base, surfaces=surf_m)
    return dict(d=d, b_all=b_all[i], b_nt=b_nt[i], b_nt_egi=b_nt_egi, s1=s1, m1=m1)


def main():
    train = [fl["name"] for fl in flights("train") if fl["profile"] == "aggressive"]
    tr = [prep(n) for n in train]
    te = {n: prep(n) for n in TESTS}
    print("# Matched anti-alias filtering of the surface channels (oracle)\n")
    print("| estimator | " + " | ".join(TESTS) + " |")
    print("|---|" + "---|" * len(TESTS))
    print("| S1 memoryless Ay inversion, sampled surfaces 30 ms back (as the filter does), truth q̄/mass/α | " +
          " | ".join(f"{mae(p['s1'] - p['b_all']):.3f}" for p in te.values()) + " |")
    print("| M1 the same with surfaces through the IMU's anti-alias filter | " +
          " | ".join(f"{mae(p['m1'] - p['b_all']):.3f}" for p in te.values()) + " |")
    for key, label in (("s1", "S1"), ("m1", "M1")):
        for ref, rlabel in (("b_nt_egi", "EGI kinematics (non-turbulent wind exact)"), ("b_nt", "non-turbulent β exact")):
            mk = lambda p: np.stack(lags(p[key] - p[ref], 5) + lags(p["d"]["rudder_deg"], 5) + [np.ones_like(p["b_all"])], axis=1)
            x = np.concatenate([mk(p) for p in tr])
            y = np.concatenate([p["b_all"] - p[ref] for p in tr])
            w, *_ = np.linalg.lstsq(x, y, rcond=None)
            print(f"| {rlabel} + linear causal estimate of the rest from {label} and rudder (lags 0..5) | " +
                  " | ".join(f"{mae(mk(p) @ w + p[ref] - p['b_all']):.3f}" for p in te.values()) + " |")
    print("| shipped hybrid | " + " | ".join(f"{mae(p['d']['err']):.3f}" for p in te.values()) + " |")


if __name__ == "__main__":
    main()
