"""(a) Where the β error of the shipped estimator concentrates, per test flight.

Needs: $WORK/run-<flight>/ and $WORK/replay/<flight>.npz of the 4 test flights.
usage: nice -n 19 <repo>/.venv/bin/python a_where.py > "$WORK/out/a_where.md"
"""
import numpy as np

from common import mae
from frames import ZONE_NAMES, beta_dot_deg_s, table

TESTS = ["test_gentle_00", "test_high-alpha_01", "test_climb-descent_02", "test_aggressive_03"]


def body_y_of_ned(d, vn, ve, vd):
    """Body-y component of an NED vector with the truth attitude (deg columns)."""
    phi, th, psi = (np.radians(d[k]) for k in ("phi_deg", "theta_deg", "psi_deg"))
    sf, cf, st, ct, sp, cp = np.sin(phi), np.cos(phi), np.sin(th), np.cos(th), np.sin(psi), np.cos(psi)
    return (sf * st * cp - cf * sp) * vn + (sf * st * sp + cf * cp) * ve + sf * ct * vd


def spearman(a, b):
    ra = np.argsort(np.argsort(a))
    rb = np.argsort(np.argsort(b))
    return np.corrcoef(ra, rb)[0, 1]


def variables(d):
    v = {}
    v["|p| gyro, deg/s"] = np.degrees(np.abs(d["gyro_p_rps"]))
    v["|r| gyro, deg/s"] = np.degrees(np.abs(d["gyro_r_rps"]))
    v["alpha true, deg"] = d["alpha_deg"]
    v["|beta| true, deg"] = np.abs(d["beta_deg"])
    v["|beta_dot| true, deg/s"] = np.abs(beta_dot_deg_s(d))
    v["qbar true, kPa"] = d["qbar_pa"] / 1000
    v["mach"] = d["mach"]
    v["nz, g"] = d["nz_g"]
    v["|Ay| sensed, m/s2"] = np.abs(d["accel_y_mps2"])
    v["|rudder|, deg"] = np.abs(d["rudder_deg"])
    v["|aileron|, deg"] = np.abs(d["aileron_deg"])
    v["|d rudder/dt|, deg/s"] = np.abs(np.gradient(d["rudder_deg"], 0.05))
    v["|d aileron/dt|, deg/s"] = np.abs(np.gradient(d["aileron_deg"], 0.05))
    if "r120" in d:
        r = d["r120"]
        # lateral (body-y) turbulence velocity, m/s, at the samples and its 1-frame change
        ty = body_y_of_ned(d, d["rp_atmosphere__turb_north_fps"], d["rp_atmosphere__turb_east_fps"],
                           d["rp_atmosphere__turb_down_fps"]) * 0.3048
        v["|turb v_body|, m/s"] = np.abs(ty)
        v["|d turb v_body| per frame, m/s"] = np.abs(np.concatenate([[0], np.diff(ty)]))
        v["|r_turb|, deg/s"] = np.degrees(np.abs(d["rp_atmosphere__r_turb_rad_sec"]))
        v["|p_turb|, deg/s"] = np.degrees(np.abs(d["rp_atmosphere__p_turb_rad_sec"]))
    return v


def main():
    print("# (a) Where the shipped estimator's β error concentrates\n")
    print("Shipped egi-hybrid, host firmware, clean link, every frame answered. err = β̂ − β_true.\n")
    print("| flight | frames | MAE | RMSE | share of frames abs(err)>0.5° | share of Σabs(err) from them | MAE of the rest | MAE if those frames were perfect (overall effect) |")
    print("|---|---|---|---|---|---|---|---|")
    tabs = {n: table(n) for n in TESTS}
    for n, d in tabs.items():
        e = d["err"]
        big = np.abs(e) > 0.5
        print(f"| {n} | {len(e)} | {mae(e):.3f} | {np.sqrt(np.mean(e**2)):.3f} | {big.mean()*100:.1f} % | "
              f"{np.abs(e[big]).sum()/np.abs(e).sum()*100:.1f} % | {mae(e[~big]):.3f} | {np.abs(e[~big]).sum()/len(e):.3f} |")
    d = tabs["test_aggressive_03"]
    e = d["err"]
    ae = np.abs(e)
    print("\n## test_aggressive_03: MAE by quintile of each variable (Spearman of abs(err) with it)\n")
    print("| variable | ρ | Q1 range → MAE | Q2 | Q3 | Q4 | Q5 range → MAE |")
    print("|---|---|---|---|---|---|---|")
    rows = []
    for k, x in variables(d).items():
        qs = np.quantile(x, [0, .2, .4, .6, .8, 1])
        cells = []
        for i in range(5):
            m = (x >= qs[i]) & (x <= qs[i + 1]) if i == 4 else (x >= qs[i]) & (x < qs[i + 1])
            cells.append((qs[i], qs[i + 1], ae[m].mean()))
        rows.append((abs(spearman(ae, x)), k, spearman(ae, x), cells))
    for _, k, rho, cells in sorted(rows, reverse=True):
        c = [f"{lo:.3g}–{hi:.3g} → **{m:.3f}**" if i in (0, 4) else f"{m:.3f}" for i, (lo, hi, m) in enumerate(cells)]
        print(f"| {k} | {rho:+.2f} | " + " | ".join(c) + " |")
    if "rp_maneuver__zone" in d:
        print("\n## test_aggressive_03 by maneuver zone\n")
        print("| zone | share of time | MAE | share of Σabs(err) |")
        print("|---|---|---|---|")
        z = np.round(d["rp_maneuver__zone"]).astype(int)
        for k in sorted(set(z)):
            m = z == k
            print(f"| {ZONE_NAMES.get(k, k)} | {m.mean()*100:.1f} % | {ae[m].mean():.3f} | {ae[m].sum()/ae.sum()*100:.1f} % |")
    # Same profile statistics on every test flight: how hard each flight is
    print("\n## Flight activity (median / 95th percentile)\n")
    print("| flight | abs(p) deg/s | abs(r) deg/s | abs(β̇) deg/s | abs(Ay) m/s² | qbar kPa | turbulence severity | abs(Δ turb v_body) per frame m/s |")
    print("|---|---|---|---|---|---|---|---|")
    for n, dd in tabs.items():
        v = variables(dd)
        sev = np.max(dd["rp_atmosphere__turbulence__milspec__severity"]) if "r120" in dd else float("nan")
        cols = ["|p| gyro, deg/s", "|r| gyro, deg/s", "|beta_dot| true, deg/s", "|Ay| sensed, m/s2", "qbar true, kPa"]
        cells = [f"{np.median(v[c]):.2f} / {np.quantile(v[c], .95):.2f}" for c in cols]
        tv = v.get("|d turb v_body| per frame, m/s")
        tcell = f"{np.median(tv):.3f} / {np.quantile(tv, .95):.3f}" if tv is not None else "-"
        print(f"| {n} | " + " | ".join(cells) + f" | {sev:.0f} | {tcell} |")
    # time series of error bursts: list the 10 worst 5-s windows
    print("\n## test_aggressive_03: the ten 5-s windows with the largest Σabs(err)\n")
    print("| t, s | MAE in window | share of flight Σabs(err) | max abs(p) deg/s | max abs(β̇) deg/s | max abs(rudder) deg | zone |")
    print("|---|---|---|---|---|---|---|")
    w = 100
    sums = np.array([ae[i:i + w].sum() for i in range(0, len(ae) - w + 1, w)])
    order = np.argsort(sums)[::-1][:10]
    bd = np.abs(beta_dot_deg_s(d))
    for j in order:
        s = slice(j * w, j * w + w)
        z = np.round(d["rp_maneuver__zone"][s]).astype(int) if "rp_maneuver__zone" in d else [0]
        zn = "/".join(sorted({ZONE_NAMES.get(int(k), str(k)) for k in z}))
        print(f"| {d['time_s'][j*w]:.0f}–{d['time_s'][j*w]+5:.0f} | {ae[s].mean():.3f} | {sums[j]/ae.sum()*100:.1f} % | "
              f"{np.degrees(np.abs(d['gyro_p_rps'][s])).max():.0f} | {bd[s].max():.1f} | {np.abs(d['rudder_deg'][s]).max():.1f} | {zn} |")
    print(f"\n(top-10 windows = {sums[order].sum()/ae.sum()*100:.1f} % of the flight's Σabs(err) in {10*w/len(ae)*100:.1f} % of its time)")


if __name__ == "__main__":
    main()
