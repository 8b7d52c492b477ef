"""(d)+(e) Turbulence and EGI timing: split β_true into a maneuver part and a turbulence part, and
test what the shipped error is made of; oracle estimators that know one part exactly.

β_true = asin(v_b/|v|), v_air,body = C_bn(φ,θ,ψ)·(v_ground − w_total) (checked to 1e-9).
β_noturb: the same with the wind less its turbulence (steady wind + 1-cos gusts), β_turb = β_true − β_noturb.

Needs: $WORK/run-<flight>/ and $WORK/replay/<flight>.npz of the 4 test flights.
usage: nice -n 19 <repo>/.venv/bin/python d_turb.py > "$WORK/out/d_turb.md"
"""
import numpy as np

from common import FT, LEVER, butter_lowpass_zero_phase, imu_filter_120, mae
from frames import table

TESTS = ["test_gentle_00", "test_high-alpha_01", "test_climb-descent_02", "test_aggressive_03"]


def cbn(phi, th, psi):
    sf, cf, st, ct, sp, cp = np.sin(phi), np.cos(phi), np.sin(th), np.cos(th), np.sin(psi), np.cos(psi)
    return np.array([
        [ct * cp, ct * sp, -st],
        [sf * st * cp - cf * sp, sf * st * sp + cf * cp, sf * ct],
        [cf * st * cp + sf * sp, cf * st * sp - sf * cp, cf * ct],
    ])  # shape 3×3×N


def beta_of(c, vn, ve, vd):
    vb = np.einsum("ijn,jn->in", c, np.array([vn, ve, vd]))
    return np.degrees(np.arcsin(vb[1] / np.linalg.norm(vb, axis=0))), vb


def beta_120(r, wind_ned):
    c = cbn(r["attitude__phi_rad"], r["attitude__theta_rad"], r["attitude__psi_rad"])
    v = np.array([r["velocities__v_north_fps"], r["velocities__v_east_fps"], r["velocities__v_down_fps"]]) * FT
    b, _ = beta_of(c, *(v - wind_ned))
    return b


def parts(d):
    r = d["r120"]
    wt = np.array([r["atmosphere__total_wind_north_fps"], r["atmosphere__total_wind_east_fps"],
                   r["atmosphere__total_wind_down_fps"]]) * FT
    turb = np.array([r["atmosphere__turb_north_fps"], r["atmosphere__turb_east_fps"], r["atmosphere__turb_down_fps"]]) * FT
    b_all = beta_120(r, wt)
    b_nt = beta_120(r, wt - turb)
    return b_all, b_nt


def egi_beta(d, wind_ned):
    """β from the EGI channels (velocity moved from the IMU to the CG with the sensed gyros, as the
    filter does) and a given wind at the frame."""
    c = cbn(d["egi_roll_rad"], d["egi_pitch_rad"], d["egi_heading_rad"])
    w = np.array([d["gyro_p_rps"], d["gyro_q_rps"], d["gyro_r_rps"]])
    lever = np.cross(w.T, LEVER).T  # ω × r, body
    v = np.array([d["egi_v_north_mps"], d["egi_v_east_mps"], d["egi_v_down_mps"]])
    v_cg = v - np.einsum("jin,jn->in", c, lever)  # C_nb (ω × r) = C_bnᵀ (ω × r)
    b, _ = beta_of(c, *(v_cg - wind_ned))
    return b


def main():
    print("# (d) Turbulence and (e) EGI timing\n")
    print("## Size of the turbulence part of β (β_turb = β_true − β with the turbulence removed from the wind)\n")
    print("| flight | severity | MAE β_turb | std β_turb | std of β_turb change per frame (50 ms) | per 120 Hz step | MAE β_turb(t) − β_turb(t−40 ms) | MAE β_noturb(t) − β_noturb(t−40 ms) |")
    print("|---|---|---|---|---|---|---|---|")
    tabs = {n: table(n) for n in TESTS}
    cache = {}
    for n, d in tabs.items():
        r = d["r120"]
        b_all, b_nt = parts(d)
        chk = np.max(np.abs(b_all - np.degrees(r["aero__beta_rad"])))
        assert chk < 1e-6, chk
        bt = b_all - b_nt
        cache[n] = (b_all, b_nt, bt)
        i = d["idx120"]
        sev = r["atmosphere__turbulence__milspec__severity"].max()
        print(f"| {n} | {sev:.0f} | {mae(bt[i]):.3f} | {bt[i].std():.3f} | {np.diff(bt[i]).std():.3f} | {np.diff(bt).std():.4f} | "
              f"{mae(bt[i] - bt[i - 5]):.3f} | {mae(b_nt[i] - b_nt[i - 5]):.3f} |")

    print("\n## What the shipped error is made of (least squares of err on the parts, per flight)\n")
    print("err = β̂ − β_true. Columns: correlation of err with −β_turb_HP (turbulence part above 0.5 Hz) and with −β_noturb_HP;")
    print("MAE after removing the best-fitting multiple of each (diagnostic, fitted on the flight itself).\n")
    print("| flight | MAE | corr(err, −β_turb HP>0.5Hz) | corr(err, −β_noturb HP>0.5Hz) | MAE − k·β_turb,HP removed | MAE − k·β_noturb,HP removed |")
    print("|---|---|---|---|---|---|")
    for n, d in tabs.items():
        b_all, b_nt, bt = cache[n]
        i = d["idx120"]
        e = d["err"]
        bth = bt[i] - butter_lowpass_zero_phase(bt[i], 0.5)
        bnh = b_nt[i] - butter_lowpass_zero_phase(b_nt[i], 0.5)
        def rm(x):
            k = (e @ x) / (x @ x)
            return mae(e - k * x)
        print(f"| {n} | {mae(e):.3f} | {np.corrcoef(e, -bth)[0,1]:+.2f} | {np.corrcoef(e, -bnh)[0,1]:+.2f} | {rm(bth):.3f} | {rm(bnh):.3f} |")

    print("\n## Oracles: one part known exactly, the other as a causal estimator could have it\n")
    print("| flight | hybrid | β_noturb exact + β_turb through IMU filter | β_noturb exact + β_turb 40 ms late | β_noturb exact + β_turb 1-s low-passed (causal, 1st order) | β_noturb 40 ms late + β_turb exact | β_noturb exact + β_turb 0 |")
    print("|---|---|---|---|---|---|---|")
    for n, d in tabs.items():
        b_all, b_nt, bt = cache[n]
        i = d["idx120"]
        bt_f = imu_filter_120(bt)
        lp = np.empty_like(bt)
        a = 1 - np.exp(-1 / 120.0)
        s = 0.0
        for k, v in enumerate(bt):
            s += a * (v - s)
            lp[k] = s
        print(f"| {n} | {mae(d['err']):.3f} | {mae(b_nt[i] + bt_f[i] - b_all[i]):.3f} | {mae(b_nt[i] + bt[i-5] - b_all[i]):.3f} | "
              f"{mae(b_nt[i] + lp[i] - b_all[i]):.3f} | {mae(b_nt[i-5] + bt[i] - b_all[i]):.3f} | {mae(b_nt[i] - b_all[i]):.3f} |")

    print("\n## (e) EGI timing: β from the EGI channels with the TRUE total wind at the frame\n")
    print("Any error here comes from the EGI's age/hold (latency 20 ms + per-flight output phase), its noise, and the")
    print("attitude/velocity mismatch. Compared with β_true at the frame and at the best delay.\n")
    print("| flight | MAE vs β_true(t) | best delay τ (ms) | MAE vs β_true(t − τ) | EGI velocity age at the frames (ms, from truth) |")
    print("|---|---|---|---|---|")
    for n, d in tabs.items():
        r = d["r120"]
        i = d["idx120"]
        wt = np.array([r["atmosphere__total_wind_north_fps"], r["atmosphere__total_wind_east_fps"],
                       r["atmosphere__total_wind_down_fps"]])[:, i] * FT
        be = egi_beta(d, wt)
        b120 = np.degrees(r["aero__beta_rad"])
        best = min(((mae(be - b120[i - k]), k) for k in range(0, 12)))
        # velocity age: which delay of the truth CG north velocity best matches the EGI north velocity
        vn = r["velocities__v_north_fps"] * FT
        age = min(((np.mean(np.abs(d["egi_v_north_mps"] - vn[i - k])), k) for k in range(0, 12)))[1]
        print(f"| {n} | {mae(be - d['beta_deg']):.3f} | {best[1]*1000/120:.1f} | {best[0]:.3f} | {age*1000/120:.1f} |")


if __name__ == "__main__":
    main()
