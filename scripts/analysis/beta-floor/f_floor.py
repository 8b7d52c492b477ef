"""Causal floors for the turbulence part of β on the aggressive flights (fit on the 16 aggressive
training flights, score on the test flights; replays needed: replay120.py).

F1  perfect Ay (no rudder chatter, no model error): β_turb(t) from its own IMU-filtered samples,
    linear in the last N frames (the best a deconvolution of the anti-alias filter can do).
F2  realistic: z = β_S1 (sensed-Ay inversion, c_physics.py S1, truth q̄/mass/α) − β_noturb_EGI
    (EGI kinematics with the non-turbulent wind exact); β_turb from the last N frames of z and of the
    rudder/aileron terms. β̂ = β_noturb_EGI + that.
Also: the size of the rudder-chatter term the accelerometers see but the 20 Hz rudder samples miss.

Needs: $WORK/run-<flight>/ and $WORK/replay/ of the test and the 16 aggressive training flights.
usage: nice -n 19 <repo>/.venv/bin/python f_floor.py > "$WORK/out/f_floor.md"
"""
import numpy as np

from c_physics import R, invert
from common import FT, flights, imu_filter_120, mae, side_parts
from d_turb import egi_beta, parts
from frames import table

TESTS = ["test_gentle_00", "test_high-alpha_01", "test_climb-descent_02", "test_aggressive_03"]


def lags(x, n):
    cols = [x]
    for k in range(1, n + 1):
        cols.append(np.concatenate([np.full(k, x[0]), x[:-k]]))
    return cols


def prep(name):
    d = table(name)
    r = d["r120"]
    i = d["idx120"]
    b_all, b_nt = parts(d)
    bt = b_all - b_nt
    # EGI kinematic β with the non-turbulent wind exact (wind at the frame)
    w_nt = (np.array([r["atmosphere__total_wind_north_fps"], r["atmosphere__total_wind_east_fps"], r["atmosphere__total_wind_down_fps"]])
            - np.array([r["atmosphere__turb_north_fps"], r["atmosphere__turb_east_fps"], r["atmosphere__turb_down_fps"]]))[:, i] * FT
    b_nt_egi = egi_beta(d, w_nt)
    s1 = invert(d, qbar=d["qbar_pa"], mass=d["mass_kg"], alpha=R(d["alpha_deg"]), mach=d["mach"], tas=d["vt_mps"], surf_delay=0.03)
    slope, _ = side_parts(R(d["alpha_deg"]), d["mach"], 0, 0, 0, 0, d["vt_mps"])
    rud = np.degrees(0.086 * R(d["rudder_deg"]) / -slope)
    ail = np.degrees(-0.0226 * R(d["aileron_deg"]) / -slope)
    # rudder chatter seen by the filtered accelerometer but not by the 20 Hz rudder samples (β units):
    # IMU-filtered 120 Hz CYdr term minus the 30-ms-delayed sampled one
    slope120, _ = side_parts(r["aero__alpha_rad"], r["velocities__mach"], 0, 0, 0, 0, r["velocities__vt_fps"] * FT)
    rud120 = np.degrees(0.086 * r["fcs__rudder_pos_rad"] / -slope120)
    rud_f = imu_filter_120(rud120)[i]
    from c_physics import delayed
    chatter = rud_f - delayed(rud120[i], 0.03)
    bt_f = imu_filter_120(bt)[i]
    return dict(d=d, bt=bt[i], b_nt=b_nt[i], b_all=b_all[i], bt_f=bt_f, b_nt_egi=b_nt_egi, s1=s1, rud=rud, ail=ail, chatter=chatter)


def fit(rows, make, target):
    x = np.concatenate([make(p) for p in rows])
    y = np.concatenate([target(p) for p in rows])
    w, *_ = np.linalg.lstsq(x, y, rcond=None)
    return w


def main():
    train = [fl["name"] for fl in flights("train") if fl["profile"] == "aggressive"]
    tr = [prep(n) for n in train]
    te = {n: prep(n) for n in TESTS}
    print("# Causal floors for the turbulence part of β\n")
    print("Fitted on the 16 aggressive training flights (replayed at 120 Hz), scored on the test flights. MAE, deg.\n")
    print("## Rudder chatter the accelerometer sees but the 20 Hz rudder samples cannot tell (β-equivalent)\n")
    print("| flight | MAE of IMU-filtered δr term − sampled δr term (30 ms back) | std |")
    print("|---|---|---|")
    for n, p in te.items():
        print(f"| {n} | {mae(p['chatter']):.3f} | {p['chatter'].std():.3f} |")
    print("\n## Floors\n")
    one = lambda p: np.ones_like(p["bt"])
    rows = []
    for nlag in (0, 2, 5, 10):
        mk1 = lambda p, n=nlag: np.stack(lags(p["bt_f"], n) + [one(p)], axis=1)
        w1 = fit(tr, mk1, lambda p: p["bt"])
        mk2 = lambda p, n=nlag: np.stack(lags(p["s1"] - p["b_nt_egi"], n) + lags(p["rud"], n) + lags(p["ail"], n) + [one(p)], axis=1)
        w2 = fit(tr, mk2, lambda p: p["b_all"] - p["b_nt_egi"])
        r1 = {n: mae(mk1(p) @ w1 + p["b_nt"] - p["b_all"]) for n, p in te.items()}
        r2 = {n: mae(mk2(p) @ w2 + p["b_nt_egi"] - p["b_all"]) for n, p in te.items()}
        rows.append((nlag, r1, r2))
    print("| estimator | N lags | " + " | ".join(TESTS) + " |")
    print("|---|---|" + "---|" * len(TESTS))
    for nlag, r1, r2 in rows:
        print(f"| F1 β_noturb exact + linear deconvolution of IMU-filtered β_turb | {nlag} | " + " | ".join(f"{r1[n]:.3f}" for n in TESTS) + " |")
    for nlag, r1, r2 in rows:
        print(f"| F2 β_noturb,EGI (non-turbulent wind exact) + linear estimate from sensed-Ay inversion & surfaces | {nlag} | " + " | ".join(f"{r2[n]:.3f}" for n in TESTS) + " |")
    print("| reference: β_noturb exact + β_turb through the IMU filter (no deconvolution) | – | " +
          " | ".join(f"{mae(p['b_nt'] + p['bt_f'] - p['b_all']):.3f}" for p in te.values()) + " |")
    print("| reference: β_noturb,EGI + β_turb exact (EGI timing/noise only) | – | " +
          " | ".join(f"{mae(p['b_nt_egi'] + p['bt'] - p['b_all']):.3f}" for p in te.values()) + " |")
    print("| shipped hybrid | – | " + " | ".join(f"{mae(p['d']['err']):.3f}" for p in te.values()) + " |")


if __name__ == "__main__":
    main()


def extra():
    """F3/F4: does knowing the rotational turbulence (F3, truth) or the sampled rudder + gyro r (F4,
    sensed) add to F1's perfect-Ay deconvolution? Linear, same fit/score split."""
    train = [fl["name"] for fl in flights("train") if fl["profile"] == "aggressive"]
    def prep2(n):
        p = prep(n)
        d = p["d"]
        p["rturb"] = np.degrees(d["rp_atmosphere__r_turb_rad_sec"])
        p["pturb"] = np.degrees(d["rp_atmosphere__p_turb_rad_sec"])
        p["gr"] = np.degrees(d["gyro_r_rps"])
        p["rudn"] = d["rudder_deg"]
        p["sat"] = (np.abs(d["rudder_deg"]) > 29.9).astype(float)
        return p
    tr = [prep2(n) for n in train]
    te = {n: prep2(n) for n in TESTS}
    one = lambda p: np.ones_like(p["bt"])
    N = 5
    mk = {
        "F1 (perfect IMU-filtered β_turb, lags 0..5)": lambda p: np.stack(lags(p["bt_f"], N) + [one(p)], axis=1),
        "F3 = F1 + true r_turb, p_turb (lags 0..5)": lambda p: np.stack(lags(p["bt_f"], N) + lags(p["rturb"], N) + lags(p["pturb"], N) + [one(p)], axis=1),
        "F4 = F1 + sensed rudder, saturation flag, gyro r (lags 0..5)": lambda p: np.stack(lags(p["bt_f"], N) + lags(p["rudn"], N) + lags(p["sat"] * np.sign(p["rudn"]), N) + lags(p["gr"], N) + [one(p)], axis=1),
    }
    print("\n## Does an undelayed turbulence cue add to the perfect-Ay floor? (β_noturb exact in all)\n")
    print("| estimator | " + " | ".join(TESTS) + " |")
    print("|---|" + "---|" * len(TESTS))
    for k, f in mk.items():
        w = fit(tr, f, lambda p: p["bt"])
        print(f"| {k} | " + " | ".join(f"{mae(f(p) @ w + p['b_nt'] - p['b_all']):.3f}" for p in te.values()) + " |")


if __name__ == "__main__":
    extra()
