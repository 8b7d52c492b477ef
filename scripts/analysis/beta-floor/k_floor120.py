"""β error floor for an estimator that reads the IMU unit's 120 Hz outputs (egi120 suite), beside the
6 Hz anti-alias floor of i_sensor_floor.py, on the current dataset (format 5).

Oracle (as F1 in f_floor.py / i_sensor_floor.py): β_noturb exact; β_turb recovered from the sensor
path's output. 6 Hz: lag 3 ms + 6 Hz Butterworth, 20 Hz frames, lags 0..5 frames. 120 Hz: the 3 ms
first-order discrete lag only (hil_sim::sensors ImuAxis::filter, α = 1 − exp(−dt/τ) per 120 Hz step),
read at the 120 Hz steps idx−j (j = 0..L−1; j = 0..5 are sub5..sub0 of the frame) at the 20 Hz
sample instants idx. Linear causal deconvolution + constant, least squares on the 16 aggressive
training flights, scored on the 4 test flights.

Accelerometer error ("real"): e_Ay = accel_y_mps2_sub* (the unit's output, reassembled into the full
120 Hz series) − lag(f_y,IMU true) where f_IMU true = fb_total/m + ω̇×r + ω×(ω×r) from the replay
(the inputs hil-sim feeds the sensor model). It carries every error of the model (scale factor,
misalignment, turn-on and in-run bias, white noise, Δv quantization). Converted to β with the
oracle's truth: δβ = e_Ay·m / (∂F_y,body/∂β), ∂F_y,body/∂β ≈ q̄S·(CYβ − C_D − β·∂C_D/∂β) from the
replay's JSBSim terms (common.side_force_slope_lbs; on the F-16 CYβ(M) − C_D, its drag having no β
term; on the f15 and c172p the CDbeta term, of |β|, adds −2·CDβ·|β| to the slope).
Rotational turbulence ("+ rotational turbulence"): the lateral force of the side force's aero-rate
terms less what they give with the gyros' body rates (common.turbulence_side_force_lbs: JSBSim's
C_Yp, C_Yr read velocities/p-, r-aero-rad_sec, the body rates less the turbulence's), turned into β
as e_Ay is and added through the same lag: a force no sensor model accounts for.
Surface sensors ("+ surface sensor errors"): the side force of each sensed surface's term
(common.surface_terms) per unit of the surface, times the dataset's 120 Hz sample less the replay's
truth, taken from the force as an estimator that subtracts the surfaces' side force would; added
without the IMU's lag (the surfaces' sensors have none), so the lag-inverting fit amplifies it a
little (f15: 0.0430 without the fit, 0.0441 with it).
"White" variant: e_Ay minus its 2-s centred moving mean (its slow part, bias and the misalignment
and scale-factor errors on slow forces, removed; noise, quantization and the fast part kept).

The deconvolution is fitted on the dataset's aggressive training flights (16 in `large`, 4 in `paper`).

usage: [AIRCRAFT=f15] DATA=... WORK=... nice -n 19 <repo>/.venv/bin/python k_floor120.py > "$WORK/out/k_floor120.md"
"""
import sys

import numpy as np

from common import (AIRCRAFT, FT, LEVER, beta_term_slopes, butter_120, flights, imu_filter_120, imu_lag_120, mae,
                    key, manifest, per_unit, rate_terms, side_force_slope_lbs, surface_terms, turbulence_side_force_lbs)
from d_turb import parts
from f_floor import TESTS, lags
from frames import table

SLUG_KG = 14.593902937
PSF_PA = 47.880258889
LBF_N = 4.4482216152605


def sub_series(d, ch, n120):
    """The unit's full 120 Hz output of channel `ch` from the *_sub0..5 columns (frame n's sub k is
    step 6n + k; sub5 the sample instant 6n + 5)."""
    s = np.stack([d[f"{ch}_sub{k}"] for k in range(6)], 1).reshape(-1)
    assert len(s) == n120, (len(s), n120)
    return s


def shift(x, k):
    return np.concatenate([np.full(k, x[0]), x[:-k]]) if k else x


def prep(n):
    d = table(n)
    r = d["r120"]
    i = d["idx120"]
    n120 = len(r["simulation__sim_time_sec"])
    b_all, b_nt = parts(d)
    bt = b_all - b_nt
    # true specific force at the IMU, y axis (hil_sim::sensors::specific_force_at)
    ms = r["inertia__mass_slugs"]
    fy_cg = r["forces__fby_total_lbs"] / ms * FT
    p, q, rr = r["velocities__pi_rad_sec"], r["velocities__qi_rad_sec"], r["velocities__ri_rad_sec"]
    pd, rd = r["accelerations__pdot_rad_sec2"], r["accelerations__rdot_rad_sec2"]
    rx, ry, rz = LEVER
    fy_imu = fy_cg + (rd * rx - pd * rz) + (q * (p * rx + q * ry + rr * rz) - ry * (p * p + q * q + rr * rr))
    u = sub_series(d, "accel_y_mps2", n120)
    e_ay = u - imu_lag_120(fy_imu)
    # consistency: the 20 Hz channel is the biquad over the unit's outputs
    chk = np.max(np.abs(butter_120(u)[i] - d["accel_y_mps2"]))
    # m/s² → β (deg), oracle truth
    k_beta = np.degrees(ms * SLUG_KG / (side_force_slope_lbs(r) * LBF_N))
    # the same without the β term of the drag (q̄S·(CYβ − C_D)), for comparison only
    k_beta0 = np.degrees(ms * SLUG_KG / ((beta_term_slopes(r)[0] - r["forces__fwx_aero_lbs"]) * LBF_N))
    e_b = e_ay * k_beta
    w = 240  # 2 s centred moving mean of e_Ay: its slow part (bias, misalignment·f)
    slow = np.convolve(e_ay, np.ones(w) / w, mode="same")
    e_b_white = (e_ay - slow) * k_beta
    # 6 Hz channel with its real error: (channel − Butterworth∘lag of the truth) in β at the frames
    e20 = (d["accel_y_mps2"] - butter_120(imu_lag_120(fy_imu))[i]) * k_beta[i]
    lagged = imu_lag_120(bt)
    # The rotational turbulence's lateral force (the side force's aero-rate terms less what the gyros'
    # body rates give them), in β as the accelerometer error is: a force the oracle cannot tell from β.
    e_b_rot = turbulence_side_force_lbs(r) / ms * FT * k_beta
    rot_lagged = imu_lag_120(e_b_rot)  # through the accelerometer, as the turbulent β is
    # The surface sensors' errors: the side force an estimator computes from the sensed surfaces (the
    # unit's 120 Hz samples, truth + ADC noise, quantized) less the true one, which it takes from the
    # lateral force before reading β.
    d_y = np.zeros(n120)
    surf_std = {}
    for term, prop, col, factor in surface_terms():
        true = r[key(prop)]
        err = sub_series(d, col, n120) * factor - true
        surf_std[col] = float(np.std(err) / factor)
        d_y = d_y + per_unit(r[key(term)], true) * err
    e_b_surf = -d_y / ms * FT * k_beta
    return dict(
        i=i, bt=bt[i], b_nt=b_nt[i], b_all=b_all[i],
        f6=imu_filter_120(bt, fc=6.0)[i],
        f6_real=imu_filter_120(bt, fc=6.0)[i] + e20,
        y120=lagged, y120_real=lagged + e_b, y120_white=lagged + e_b_white,
        y120_rot=lagged + rot_lagged, y120_real_rot=lagged + e_b + rot_lagged,
        y120_real_surf=lagged + e_b + e_b_surf, y120_all=lagged + e_b + rot_lagged + e_b_surf,
        e_b_rot_mae=mae(e_b_rot[i]), e_b_surf_mae=mae(e_b_surf[i]), surf_std=surf_std,
        gust_rate_r2=gust_rate_r2(r, bt), moments=moment_columns(d, r, i, n120),
        chk=chk, e_ay=e_ay, e_b=e_b[i], e_ay_std=e_ay.std(), e_ay_mean=e_ay.mean(),
        e_b_mae=mae(e_b), e_b_white_mae=mae(e_b_white), k_beta=np.median(np.abs(k_beta)),
        f_per_deg=np.median(1 / np.abs(k_beta[i])), f_per_deg0=np.median(1 / np.abs(k_beta0[i])),
        qbar_kpa=np.mean(r["aero__qbar_psf"][i]) * PSF_PA / 1000, mass_kg=np.mean(ms[i]) * SLUG_KG,
    )


def gust_rate_r2(r, bt):
    """{rate: R²} of each gust rate (aero less body rate, rad/s) on the turbulent β over ±1 s (every
    other 120 Hz step, least squares with a constant): how much of the rotational turbulence a
    history of the lateral gust could tell, were the gust rate the gust's own rate of change
    (MIL-F-8785C's r_g)."""
    out = {}
    for rate in ("p", "r"):
        g = (r[key(f"velocities/{rate}-aero-rad_sec")] - r[key(f"velocities/{rate}-rad_sec")])[120:-120]
        x = np.stack([bt[120 + k:len(bt) - 120 + k] for k in range(-120, 121, 2)] + [np.ones(len(g))], 1)
        w, *_ = np.linalg.lstsq(x, g, rcond=None)
        out[rate] = float(1 - np.var(g - x @ w) / max(np.var(g), 1e-30))
    return out


def moment_columns(d, r, i, n120):
    """A linear stand-in for the roll and yaw moment equations, as regressors at the frames: the
    gyros' p and r sub-samples of the frame's period over q̄ and over V (their differences are the
    angular accelerations, the moment coefficients' share of them, and the rate terms), p·q and q·r
    over q̄ (the inertial coupling), and the sensed aileron and rudder (the 120 Hz sample at the
    frame) and over q̄. q̄ and V are the replay's (the oracle's)."""
    qb, v = r["aero__qbar_psf"][i], r["velocities__vt_fps"][i]
    g = {c: sub_series(d, c, n120) for c in ("gyro_p_rps", "gyro_q_rps", "gyro_r_rps", "aileron_deg", "rudder_deg")}
    cols = []
    for c in ("gyro_p_rps", "gyro_r_rps"):
        for j in range(6):
            x = shift(g[c], j)[i]
            cols += [x / qb, x / v]
    p, q, rr = (g[c][i] for c in ("gyro_p_rps", "gyro_q_rps", "gyro_r_rps"))
    cols += [p * q / qb, q * rr / qb]
    for c in ("aileron_deg", "rudder_deg"):
        cols += [g[c][i], g[c][i] / qb]
    return np.stack(cols, 1)


def feat20(x, L):
    return np.stack(lags(x, L) + [np.ones_like(x)], 1)


def feat120(y, i, L):
    return np.stack([shift(y, j)[i] for j in range(L)] + [np.ones(len(i))], 1)


def main():
    lever = manifest()["config"]["sensors"]["imu"]["lever_arm_m"]
    assert np.allclose(lever, LEVER), (lever, LEVER)  # the dataset's IMU is where aircraft/<name>.toml says
    train = [fl["name"] for fl in flights("train") if fl["profile"] == "aggressive"]
    if len(sys.argv) > 1:
        train = train[: int(sys.argv[1])]
    tr = [prep(n) for n in train]
    te = {n: prep(n) for n in TESTS}
    nfr = {n: len(p["bt"]) for n, p in te.items()}

    def score(est):  # per-flight MAE and frame-weighted overall
        errs = {n: est(p) - p["b_all"] for n, p in te.items()}
        per = {n: mae(e) for n, e in errs.items()}
        per["overall"] = float(np.sum([np.sum(np.abs(e)) for e in errs.values()]) / sum(nfr.values()))
        return per

    def fit(make):
        x = np.concatenate([make(p) for p in tr])
        y = np.concatenate([p["bt"] for p in tr])
        w, *_ = np.linalg.lstsq(x, y, rcond=None)
        return w

    rows = []
    rows.append(("6 Hz (20 Hz frames), as filtered", score(lambda p: p["b_nt"] + p["f6"])))
    w = fit(lambda p: feat20(p["f6"], 5))
    rows.append(("6 Hz, deconvolved (lags 0..5 frames)", score(lambda p: p["b_nt"] + feat20(p["f6"], 5) @ w)))
    rows.append(("6 Hz + real accel error, as filtered", score(lambda p: p["b_nt"] + p["f6_real"])))
    w = fit(lambda p: feat20(p["f6_real"], 5))
    rows.append(("6 Hz + real accel error, deconvolved (lags 0..5 frames)", score(lambda p: p["b_nt"] + feat20(p["f6_real"], 5) @ w)))
    for key, lab in (("y120", "120 Hz lag-only (perfect accel)"), ("y120_real", "120 Hz + real accel error"),
                     ("y120_white", "120 Hz + accel noise & quantization only (slow error removed)"),
                     ("y120_rot", "120 Hz lag-only + rotational turbulence"),
                     ("y120_real_rot", "120 Hz + real accel error + rotational turbulence"),
                     ("y120_real_surf", "120 Hz + real accel error + surface sensor errors"),
                     ("y120_all", "120 Hz + real accel error + rotational turbulence + surface sensor errors")):
        rows.append((f"{lab}, as filtered (sub5)", score(lambda p, k=key: p["b_nt"] + p[k][p["i"]])))
        for L in (2, 6, 12, 18, 120, 240):
            w = fit(lambda p, k=key, L=L: feat120(p[k], p["i"], L))
            rows.append((f"{lab}, deconvolved (120 Hz lags 0..{L-1})",
                         score(lambda p, k=key, L=L, w=w: p["b_nt"] + feat120(p[k], p["i"], L) @ w)))
            if L == 6:
                print(f"<!-- weights {key} L=6: {np.array2string(w, precision=4)} -->")
    # The last floor's oracle, also reading the moment equations' regressors (moment_columns) and
    # β_noturb (the moments read the whole β).
    def with_moments(p):
        return np.concatenate([feat120(p["y120_all"], p["i"], 6), p["b_nt"][:, None], p["moments"]], 1)
    w = fit(with_moments)
    rows.append(("120 Hz + real accel error + rotational turbulence + surface sensor errors, deconvolved "
                 "(120 Hz lags 0..5), + the gyros' p and r sub-samples and the surfaces (moment_columns)",
                 score(lambda p, w=w: p["b_nt"] + with_moments(p) @ w)))
    rows.append(("reference: β_noturb exact, β_turb = 0", score(lambda p: p["b_nt"])))

    print(f"# β floor with 120 Hz IMU outputs, {AIRCRAFT} (fit: {len(tr)} aggressive training flights; MAE, deg)\n")
    cols = TESTS + ["overall"]
    print("| oracle | " + " | ".join(c.replace("test_", "") for c in cols) + " |")
    print("|---|" + "---|" * len(cols))
    for lab, per in rows:
        print(f"| {lab} | " + " | ".join(f"{per[c]:.4f}" for c in cols) + " |")
    print("\n## Accelerometer error (unit output − lag(true f_y,IMU)), test flights\n")
    print("| flight | frames | max abs(Butterworth(sub-series) − accel_y channel) | mean e_Ay m/s² | std e_Ay m/s² | median deg per m/s² | MAE e_β deg (120 Hz) | MAE white part deg |")
    print("|---|---|---|---|---|---|---|---|")
    for n, p in te.items():
        print(f"| {n} | {nfr[n]} | {p['chk']:.2e} | {p['e_ay_mean']:.2e} | {p['e_ay_std']:.2e} | {p['k_beta']:.3f} | {p['e_b_mae']:.4f} | {p['e_b_white_mae']:.4f} |")
    terms = rate_terms()
    surf = surface_terms()
    unseen = [
        ("The rotational turbulence's side force", "aero-rate terms", terms["p"] + terms["r"],
         "e_b_rot_mae", None),
        ("The surface sensors' errors in the side force", "sensed-surface terms",
         [f"{t} ({prop}, sensed as {col})" for t, prop, col, _ in surf], "e_b_surf_mae",
         lambda p: ", ".join(f"{c} {v:.4f}" for c, v in p["surf_std"].items())),
    ]
    for title, what, names, mae_key, extra in unseen:
        print(f"\n## {title}, as β, test flights\n")
        print(f"The side force's {what}: {', '.join(names) or 'none'}.\n")
        print("| flight | MAE, deg |" + (" error std per surface (sensed − true, deg) |" if extra else ""))
        print("|---|---|" + ("---|" if extra else ""))
        for n, p in te.items():
            print(f"| {n} | {p[mae_key]:.4f} |" + (f" {extra(p)} |" if extra else ""))
    print("\n## The gust rates against the turbulent β's history, test flights\n")
    print("R² of each gust rate (aero less body rate) on the turbulent β over ±1 s (`gust_rate_r2`).\n")
    print("| flight | p_g R² | r_g R² |")
    print("|---|---|---|")
    for n, p in te.items():
        print(f"| {n} | {p['gust_rate_r2']['p']:.3f} | {p['gust_rate_r2']['r']:.3f} |")
    print("\n## Lateral specific force per degree of β, test flights (medians over the frames)\n")
    print("| flight | m/s² per deg | without the drag's β term (CYβ − C_D) | mean q̄ kPa | mean mass kg |")
    print("|---|---|---|---|---|")
    for n, p in te.items():
        print(f"| {n} | {p['f_per_deg']:.3f} | {p['f_per_deg0']:.3f} | {p['qbar_kpa']:.2f} | {p['mass_kg']:.0f} |")
    print("\nTraining flights: max channel check " + f"{max(p['chk'] for p in tr):.2e}, e_Ay std " +
          ", ".join(f"{p['e_ay_std']:.2e}" for p in tr))


if __name__ == "__main__":
    main()
