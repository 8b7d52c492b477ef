"""What is left in the shipped β error after the unavoidable turbulence part, and can simple extra
inputs (linear, causal, lags 0..5) predict the rest? Corrections are fitted on the 10 validation
flights (held out of network training) or on the 16 aggressive training flights (in-sample for the
network, so optimistic), and scored on the test flights.

Needs: $WORK/run-<flight>/ of the test, validation and aggressive training flights; replays of the test and aggressive training flights.
usage: nice -n 19 <repo>/.venv/bin/python h_residual.py > "$WORK/out/h_residual.md"
"""
import numpy as np

from c_physics import R, invert
from common import EMPTY_KG, flights, isa, mae, side_parts
from f_floor import TESTS, fit, lags, prep
from frames import table
from paths import VAL_FLIGHTS

VAL = open(VAL_FLIGHTS).read().split()


def cand(d):
    """Candidate extra inputs, all from sensed data or the estimator's own outputs."""
    rho, a_s = isa(d["gps_alt_m"])
    v = d["gps_speed_mps"]
    s3 = invert(d, qbar=0.5 * rho * v * v, mass=EMPTY_KG + d["fuel_qty_kg"], alpha=R(d["alpha_hat"]), mach=v / a_s, tas=v,
                surf_delay=0.03)
    slope, _ = side_parts(R(d["alpha_hat"]), v / a_s, 0, 0, 0, 0, v)
    return {
        "beta_hat": d["beta_hat"],
        "s3_minus_hat": s3 - d["beta_hat"],
        "rud": np.degrees(0.086 * R(d["rudder_deg"]) / -slope),
        "ail": np.degrees(-0.0226 * R(d["aileron_deg"]) / -slope),
        "ay": d["accel_y_mps2"],
        "sat": np.sign(d["rudder_deg"]) * (np.abs(d["rudder_deg"]) > 29.9),
    }


SETS = {
    "C1 β̂ history (lead/lag/smoothing)": ["beta_hat"],
    "C2 C1 + Ay-inversion innovation (S3 − β̂)": ["beta_hat", "s3_minus_hat"],
    "C3 C2 + rudder, aileron terms, rudder saturation, Ay": ["beta_hat", "s3_minus_hat", "rud", "ail", "sat", "ay"],
}


def design(c, keys, n=5):
    cols = []
    for k in keys:
        cols += lags(c[k], n)
    # the β̂ column itself is the quantity being corrected; keep it (it lets the fit scale/lead it)
    cols.append(np.ones_like(c["beta_hat"]))
    return np.stack(cols, axis=1)


def main():
    print("# Residual structure of the shipped β error\n")
    # 1. unavoidable part: the F1 floor residual (perfect-Ay deconvolution, non-turbulent part exact)
    train_agg = [fl["name"] for fl in flights("train") if fl["profile"] == "aggressive"]
    tr = [prep(n) for n in train_agg]
    te = {n: prep(n) for n in TESTS}
    one = lambda p: np.ones_like(p["bt"])
    mk1 = lambda p: np.stack(lags(p["bt_f"], 5) + [one(p)], axis=1)
    w1 = fit(tr, mk1, lambda p: p["bt"])
    print("u = F1 residual (β̂_F1 − β_true): the turbulence error no accelerometer-based estimator can avoid.\n")
    print("| flight | hybrid MAE | MAE(u) | corr(err, u) | MAE(err − u) | MAE(err − k·u), k fitted on the flight |")
    print("|---|---|---|---|---|---|")
    for n, p in te.items():
        u = mk1(p) @ w1 + p["b_nt"] - p["b_all"]
        e = p["d"]["err"]
        k = (e @ u) / (u @ u)
        print(f"| {n} | {mae(e):.3f} | {mae(u):.3f} | {np.corrcoef(e, u)[0,1]:+.2f} | {mae(e - u):.3f} | {mae(e - k*u):.3f} (k={k:.2f}) |")

    print("\n## Linear causal corrections of β̂ (target β_true), lags 0..5 frames\n")
    print("| inputs | fitted on | " + " | ".join(TESTS) + " | overall |")
    print("|---|---|" + "---|" * (len(TESTS) + 1))
    tabs = {n: table(n, with_replay=False) for n in TESTS}
    cands = {n: cand(d) for n, d in tabs.items()}
    base = [tabs[n]["err"] for n in TESTS]
    print("| none (shipped) | – | " + " | ".join(f"{mae(e):.3f}" for e in base) + f" | {mae(np.concatenate(base)):.3f} |")
    fit_sets = {"10 validation flights": VAL, "16 aggressive training flights": train_agg}
    for label, names in fit_sets.items():
        trd = [table(n, with_replay=False) for n in names]
        trc = [cand(d) for d in trd]
        for sname, keys in SETS.items():
            x = np.concatenate([design(c, keys) for c in trc])
            y = np.concatenate([d["beta_deg"] for d in trd])
            w, *_ = np.linalg.lstsq(x, y, rcond=None)
            errs = [design(cands[n], keys) @ w - tabs[n]["beta_deg"] for n in TESTS]
            print(f"| {sname} | {label} | " + " | ".join(f"{mae(e):.3f}" for e in errs) + f" | {mae(np.concatenate(errs)):.3f} |")


if __name__ == "__main__":
    main()
