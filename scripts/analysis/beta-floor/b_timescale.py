"""(b) Timescale of the β error: band split, cross-correlations, lag model, lag oracle.

Lag fits (τ) are made on the 10 validation flights (held out of training by the trainer, used only
for its best-epoch choice) and on the 16 aggressive training flights, then scored on the test flights.

Needs: $WORK/run-<flight>/ of the test, validation and aggressive training flights; replays where present.
usage: nice -n 19 <repo>/.venv/bin/python b_timescale.py > "$WORK/out/b_timescale.md"
"""
import numpy as np

from common import butter_lowpass_zero_phase, flights, mae
from paths import VAL_FLIGHTS
from frames import beta_dot_deg_s, table

TESTS = ["test_gentle_00", "test_high-alpha_01", "test_climb-descent_02", "test_aggressive_03"]
VAL = open(VAL_FLIGHTS).read().split()


def xcorr(a, b, lags):
    a = (a - a.mean()) / a.std()
    b = (b - b.mean()) / b.std()
    out = []
    for k in lags:
        if k >= 0:
            out.append(np.mean(a[k:] * b[:len(b) - k]))
        else:
            out.append(np.mean(a[:k] * b[-k:]))
    return np.array(out)


def shifted_truth(d, tau):
    """β_true(t − τ) at the samples (interpolated on the 120 Hz replay when there)."""
    if "r120" in d:
        t = d["r120"]["simulation__sim_time_sec"]
        b = np.degrees(d["r120"]["aero__beta_rad"])
    else:
        t, b = d["time_s"], d["beta_deg"]
    return np.interp(d["time_s"] - tau, t, b)


def main():
    tabs = {n: table(n) for n in TESTS}
    print("# (b) Timescale of the β error\n")
    print("## Band split (zero-phase 2nd-order Butterworth at 0.5 Hz, forward-backward)\n")
    print("err = LP + HP. 'MAE saved' = MAE(err) − MAE(err − part): what removing that part alone would give.\n")
    print("| flight | MAE | MAE(LP <0.5 Hz) | MAE(HP >0.5 Hz) | saved by removing LP | saved by removing HP | MAE(HP >2 Hz) | RMS LP | RMS HP |")
    print("|---|---|---|---|---|---|---|---|---|")
    for n, d in tabs.items():
        e = d["err"]
        lp = butter_lowpass_zero_phase(e, 0.5)
        hp = e - lp
        hp2 = e - butter_lowpass_zero_phase(e, 2.0)
        print(f"| {n} | {mae(e):.3f} | {mae(lp):.3f} | {mae(hp):.3f} | {mae(e)-mae(hp):.3f} | {mae(e)-mae(lp):.3f} | {mae(hp2):.3f} | "
              f"{np.sqrt(np.mean(lp**2)):.3f} | {np.sqrt(np.mean(hp**2)):.3f} |")

    # Power spectrum of err and of β on the aggressive flight (Welch, 512-frame Hann windows)
    d = tabs["test_aggressive_03"]
    e = d["err"]
    def welch(x, nper=512):
        w = np.hanning(nper)
        segs = [x[i:i + nper] - x[i:i + nper].mean() for i in range(0, len(x) - nper + 1, nper // 2)]
        p = np.mean([np.abs(np.fft.rfft(s * w)) ** 2 for s in segs], axis=0) / (20.0 * (w ** 2).sum())
        p[1:-1] *= 2
        return np.fft.rfftfreq(nper, 0.05), p
    f, pe = welch(e)
    _, pb = welch(d["beta_deg"])
    bands = [(0, 0.1), (0.1, 0.5), (0.5, 1), (1, 2), (2, 4), (4, 10.01)]
    print("\n## test_aggressive_03: variance of err and of β truth per band (Welch)\n")
    print("| band, Hz | err variance, deg² | share of err variance | β variance, deg² | err/β amplitude ratio |")
    print("|---|---|---|---|---|")
    df = f[1] - f[0]
    tot = pe.sum() * df
    for lo, hi in bands:
        m = (f >= lo) & (f < hi)
        ve, vb = pe[m].sum() * df, pb[m].sum() * df
        print(f"| {lo}–{min(hi,10):g} | {ve:.4f} | {ve/tot*100:.1f} % | {vb:.4f} | {np.sqrt(ve/vb):.2f} |")

    # Cross-correlation of err with β̇, p, r, Ay (aggressive)
    lags = np.arange(-6, 7)
    print("\n## test_aggressive_03: normalised cross-correlation of err(t) with x(t − k·50 ms)\n")
    print("| x | " + " | ".join(f"k={k}" for k in lags) + " |")
    print("|---|" + "---|" * len(lags))
    bd = beta_dot_deg_s(d)
    for name, x in [("β̇ true", bd), ("β true", d["beta_deg"]), ("gyro p", d["gyro_p_rps"]), ("gyro r", d["gyro_r_rps"]),
                    ("accel y", d["accel_y_mps2"]), ("rudder", d["rudder_deg"]), ("aileron", d["aileron_deg"])]:
        c = xcorr(e, x, lags)
        print(f"| {name} | " + " | ".join(f"{v:+.2f}" for v in c) + " |")

    # Lag model err ≈ −τ·β̇ : τ fitted by least squares on validation / aggressive training flights
    def fit_tau(names):
        num = den = 0.0
        for n in names:
            dd = table(n, with_replay=True)
            b = beta_dot_deg_s(dd)
            num += -(dd["err"] * b).sum()
            den += (b * b).sum()
        return num / den
    agg_train = [fl["name"] for fl in flights("train") if fl["profile"] == "aggressive"]
    tau_val = fit_tau(VAL)
    tau_agg = fit_tau(agg_train)
    print("\n## Lag model err ≈ −τ·β̇_true (least squares, τ fitted off the test flights)\n")
    print(f"τ fitted on the 10 validation flights: **{tau_val*1000:.1f} ms**; on the 16 aggressive training flights "
          f"(in-sample for the network): **{tau_agg*1000:.1f} ms**.\n")
    print("| flight | MAE | τ fitted on this flight (diagnostic only) | MAE after err + τ_val·β̇ (oracle β̇) | after err + τ_agg·β̇ | share of err variance explained by β̇ (this flight) |")
    print("|---|---|---|---|---|---|")
    for n, dd in tabs.items():
        b = beta_dot_deg_s(dd)
        e = dd["err"]
        t_own = -(e * b).sum() / (b * b).sum()
        r2 = 1 - np.var(e + t_own * b) / np.var(e)
        print(f"| {n} | {mae(e):.3f} | {t_own*1000:.1f} ms | {mae(e + tau_val*b):.3f} | {mae(e + tau_agg*b):.3f} | {r2*100:.1f} % |")

    # Lag oracle: compare β̂(t) with β_true(t − τ) for a range of τ (diagnostic: how much of the error
    # is a pure delay of the truth)
    taus = np.arange(0, 0.1001, 0.01)
    print("\n## Lag oracle: MAE of β̂(t) − β_true(t − τ)\n")
    print("| flight | " + " | ".join(f"{t*1000:.0f} ms" for t in taus) + " |")
    print("|---|" + "---|" * len(taus))
    for n, dd in tabs.items():
        print(f"| {n} | " + " | ".join(f"{mae(dd['beta_hat'] - shifted_truth(dd, t)):.3f}" for t in taus) + " |")
    # pure-delay floor: what a perfect estimator delayed by τ would score (β(t) − β(t − τ))
    print("\n## Delay floor: MAE of β_true(t − τ) − β_true(t) (an otherwise perfect estimator that is τ late)\n")
    print("| flight | " + " | ".join(f"{t*1000:.0f} ms" for t in taus[1:]) + " |")
    print("|---|" + "---|" * (len(taus) - 1))
    for n, dd in tabs.items():
        print(f"| {n} | " + " | ".join(f"{mae(shifted_truth(dd, t) - dd['beta_deg']):.3f}" for t in taus[1:]) + " |")


if __name__ == "__main__":
    main()
