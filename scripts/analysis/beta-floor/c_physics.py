"""(c) Physics floor: β from the lateral specific force, Ay·m/(q̄·S) = C_Y,body(β, p, r, δa, δr, α, M).

Memoryless inversions (no fitting) with the JSBSim F-16 side/drag terms re-implemented in numpy
(common.py, tables parsed from estimator-core/src/aero/f16_tables.rs), then causal linear
"information floors" fitted on the 64 training flights and scored on the test flights.

Needs: $WORK/run-<flight>/ of the test and training flights; $WORK/replay/ of the test flights.
usage: nice -n 19 <repo>/.venv/bin/python c_physics.py > "$WORK/out/c_physics.md"
"""
import numpy as np

from common import (EMPTY_KG, FT, S_M2, beta_from_cy_body, drag_coef, flights, imu_filter_120, isa,
                    lef_schedule_rad, mae, side_parts)
from frames import table

TESTS = ["test_gentle_00", "test_high-alpha_01", "test_climb-descent_02", "test_aggressive_03"]
R = np.radians


def f_cg_y(d):
    """Sensed lateral specific force moved to the CG (lever arm [0.5, 0, 0.2] m, sensed gyros)."""
    p, q, r = d["gyro_p_rps"], d["gyro_q_rps"], d["gyro_r_rps"]
    pd = np.gradient(p, 0.05)
    rd = np.gradient(r, 0.05)
    # causal ω̇ (backward difference), as the filter does
    pd = np.concatenate([[0], np.diff(p)]) / 0.05
    rd = np.concatenate([[0], np.diff(r)]) / 0.05
    rx, rz = 0.5, 0.2
    tang = rd * rx - pd * rz  # (ω̇ × r)_y
    cent = q * (p * rx + r * rz)  # (ω × (ω × r))_y = ω_y (ω·r) − r_y |ω|²
    return d["accel_y_mps2"] - tang - cent


def flap_mix_rad(d):
    return 1.4324 * (2 * d["flaperon_deg"] / 20.0 + 2 * d["tef_deg"] / 20.0)


def delayed(x, tau, dt=0.05):
    """x at t − τ by linear interpolation between frames (τ ≤ dt uses the previous frame)."""
    k = tau / dt
    i = int(np.floor(k))
    f = k - i
    xi = np.concatenate([np.full(i, x[0]), x[:len(x) - i]]) if i > 0 else x
    xj = np.concatenate([np.full(i + 1, x[0]), x[:len(x) - i - 1]])
    return xi + f * (xj - xi)


def invert(d, *, qbar, mass, alpha, mach, tas, surf_delay=0.0, surfaces=None, rates=None, fy=None):
    fy = f_cg_y(d) if fy is None else fy
    cy = mass * fy / (qbar * S_M2)
    if surfaces is None:
        ail = R(d["aileron_deg"])
        rud = R(d["rudder_deg"])
        el = R(d["elevator_deg"])
        sb = R(d["speedbrake_deg"])
        mix = flap_mix_rad(d)
        if surf_delay > 0:
            ail, rud, el, sb, mix = (delayed(x, surf_delay) for x in (ail, rud, el, sb, mix))
    else:
        ail, rud, el, sb, mix = surfaces
    p, r = (d["gyro_p_rps"], d["gyro_r_rps"]) if rates is None else rates
    cd = drag_coef(alpha, mach, el, lef_schedule_rad(alpha, mach), sb, mix, d["gyro_q_rps"], tas) + 0.027  # gear down
    return np.degrees(beta_from_cy_body(cy, alpha, mach, ail, rud, p, r, tas, cd))


def at_samples_filtered(d, x120):
    return imu_filter_120(x120)[d["idx120"]]


def variants(d):
    """Memoryless β estimates, degrees, keyed by a description."""
    out = {}
    qbar, mass = d["qbar_pa"], d["mass_kg"]
    alpha, mach, tas = R(d["alpha_deg"]), d["mach"], d["vt_mps"]
    base = dict(qbar=qbar, mass=mass, alpha=alpha, mach=mach, tas=tas)
    r = d.get("r120")
    if r is not None:
        # the same inversion on JSBSim's own instantaneous Y force (CG) with gyro-like inertial rates
        fy_true = (r["forces__fby_total_lbs"] / r["inertia__mass_slugs"] * FT)[d["idx120"]]
        surf_true = tuple(r[k][d["idx120"]] for k in ("fcs__aileron_pos_rad", "fcs__rudder_pos_rad", "fcs__elevator_pos_rad",
                                                      "fcs__speedbrake_pos_rad", "fcs__flaperon_mix_rad"))
        out["T0 truth Ay (instantaneous, CG), truth surfaces, inertial p,r (rotational turbulence unknown)"] = invert(
            d, **base, fy=fy_true, surfaces=surf_true,
            rates=(r["velocities__pi_rad_sec"][d["idx120"]], r["velocities__ri_rad_sec"][d["idx120"]]))
        # every input through the IMU's anti-alias path (lag 3 ms + Butterworth 6 Hz): what an inversion
        # of filtered signals gives if the surfaces were filtered alike (an oracle for consistent timing)
        fy_f = at_samples_filtered(d, r["forces__fby_total_lbs"] / r["inertia__mass_slugs"] * FT)
        surf_f = tuple(at_samples_filtered(d, r[k]) for k in ("fcs__aileron_pos_rad", "fcs__rudder_pos_rad", "fcs__elevator_pos_rad",
                                                               "fcs__speedbrake_pos_rad", "fcs__flaperon_mix_rad"))
        rates_f = (at_samples_filtered(d, r["velocities__pi_rad_sec"]), at_samples_filtered(d, r["velocities__ri_rad_sec"]))
        out["T1 as T0 but Ay, p, r AND surfaces all through the IMU filter (consistent timing, ~40 ms late)"] = invert(
            d, **base, fy=fy_f, surfaces=surf_f, rates=rates_f)
        out["T2 truth β through the IMU filter (pure anti-alias delay, no model error)"] = np.degrees(
            at_samples_filtered(d, r["aero__beta_rad"]))
    out["S0 sensed Ay/gyros/surfaces at the frame, truth q̄, mass, α, Mach, V"] = invert(d, **base)
    out["S1 as S0, surfaces delayed 30 ms (the filter's choice)"] = invert(d, **base, surf_delay=0.03)
    out["S2 as S0, surfaces delayed 40 ms"] = invert(d, **base, surf_delay=0.04)
    # realistic: q̄ from ISA at GPS altitude and GPS speed (no wind), mass = empty + fuel gauge,
    # α = the shipped hybrid's own α̂
    rho, a_s = isa(d["gps_alt_m"])
    v = d["gps_speed_mps"]
    real = dict(qbar=0.5 * rho * v * v, mass=EMPTY_KG + d["fuel_qty_kg"], alpha=R(d["alpha_hat"]), mach=v / a_s, tas=v)
    out["S3 as S1 with q̄ = ½ρ_ISA(GPS alt)·V_GPS², mass = empty + fuel gauge, α = hybrid α̂"] = invert(d, **real, surf_delay=0.03)
    real_t = dict(real, qbar=qbar, tas=tas, mach=mach)
    out["S4 as S3 but true q̄ (only wind-free airspeed missing → isolated)"] = invert(d, **real_t, surf_delay=0.03)
    return out


# ---------------------------------------------------------------------------------------------
# Causal linear information floor: β(t) from the last N frames of the S1 inversion and of the
# rudder/aileron/rate terms (in β units), fitted by least squares on the training flights.
def design(d, s1, nlag=6):
    alpha, mach, tas = R(d["alpha_deg"]), d["mach"], d["vt_mps"]
    slope, _ = side_parts(alpha, mach, 0, 0, 0, 0, tas)
    cols = [s1]
    rud = np.degrees(0.086 * R(d["rudder_deg"]) / -slope)
    ail = np.degrees(-0.0226 * R(d["aileron_deg"]) / -slope)
    for x in (s1, rud, ail):
        for k in range(1, nlag + 1):
            cols.append(np.concatenate([np.full(k, x[0]), x[:-k]]))
    cols.append(rud)
    cols.append(ail)
    cols.append(np.ones_like(s1))
    return np.stack(cols, axis=1)


def fit_floor(train_names, nlag=6):
    xs, ys = [], []
    for n in train_names:
        d = table(n, with_replay=False)
        s1 = invert(d, qbar=d["qbar_pa"], mass=d["mass_kg"], alpha=R(d["alpha_deg"]), mach=d["mach"], tas=d["vt_mps"],
                    surf_delay=0.03)
        xs.append(design(d, s1, nlag))
        ys.append(d["beta_deg"])
    x = np.concatenate(xs)
    y = np.concatenate(ys)
    w, *_ = np.linalg.lstsq(x, y, rcond=None)
    return w


def main():
    print("# (c) Physics floor: β from the lateral specific force\n")
    print("MAE (deg) of each memoryless inversion against β_true at the frame instant. No fitting.\n")
    res = {}
    for n in TESTS:
        d = table(n)
        res[n] = {k: mae(v - d["beta_deg"]) for k, v in variants(d).items()}
        res[n]["hybrid (shipped)"] = mae(d["err"])
    keys = list(res["test_aggressive_03"].keys())
    print("| estimate | " + " | ".join(TESTS) + " |")
    print("|---|" + "---|" * len(TESTS))
    for k in keys:
        print(f"| {k} | " + " | ".join(f"{res[n].get(k, float('nan')):.3f}" for n in TESTS) + " |")

    print("\n## Causal linear information floor (fitted on training flights, scored on test flights)\n")
    print("β̂(t) = Σ_k a_k·β_S1(t−k) + Σ_k b_k·δr-term(t−k) + Σ_k c_k·δa-term(t−k) + const, k = 0..N frames,")
    print("β_S1 the S1 inversion (truth q̄/mass/α: an upper bound for what the network could extract), least squares.\n")
    train_all = [fl["name"] for fl in flights("train")]
    train_agg = [fl["name"] for fl in flights("train") if fl["profile"] == "aggressive"]
    print("| fitted on | N | " + " | ".join(TESTS) + " | overall |")
    print("|---|---|" + "---|" * (len(TESTS) + 1))
    for label, names in (("16 aggressive training flights", train_agg), ("all 64 training flights", train_all)):
        for nlag in (0, 3, 6, 10):
            w = fit_floor(names, nlag)
            errs = []
            for n in TESTS:
                d = table(n, with_replay=False)
                s1 = invert(d, qbar=d["qbar_pa"], mass=d["mass_kg"], alpha=R(d["alpha_deg"]), mach=d["mach"],
                            tas=d["vt_mps"], surf_delay=0.03)
                errs.append(design(d, s1, nlag) @ w - d["beta_deg"])
            tot = np.concatenate(errs)
            print(f"| {label} | {nlag} | " + " | ".join(f"{mae(e):.3f}" for e in errs) + f" | {mae(tot):.3f} |")


if __name__ == "__main__":
    main()
