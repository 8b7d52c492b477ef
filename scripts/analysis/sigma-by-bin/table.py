"""α / β error against the reported 1σ, by bin: table.py DATASET_CSV ESTIMATES_CSV (run.sh)."""
import csv
import sys

import numpy as np


def columns(path, names):
    with open(path) as f:
        rows = csv.DictReader(f)
        data = {n: [] for n in names}
        for r in rows:
            for n in names:
                data[n].append(float(r[n]) if r[n] != "" else np.nan)
    return {n: np.array(v) for n, v in data.items()}


truth = columns(sys.argv[1], ["time_s", "vt_mps", "tef_deg", "alpha_deg", "wind_down_mps"])
est = columns(sys.argv[2], ["time_s", "received", "alpha_true_deg", "alpha_deg", "sigma_alpha_deg",
                            "beta_true_deg", "beta_deg", "sigma_beta_deg"])
# The vertical wind's departure from its 30-s centred mean (the ends: what the window holds), over
# the airspeed: the gust's angle, on the whole flight before frames are matched.
w = truth["wind_down_mps"]
c = np.concatenate([[0.0], np.cumsum(w)])
i = np.arange(len(w))
lo, hi = np.maximum(0, i - 300), np.minimum(len(w), i + 300)
truth["gust_deg"] = np.degrees(np.abs(w - (c[hi] - c[lo]) / (hi - lo)) / truth["vt_mps"])
# Frames are matched by their 20 Hz index; lost frames carry no estimate.
frame = {int(round(t * 20)): i for i, t in enumerate(truth["time_s"])}
pick = np.array([frame.get(int(round(t * 20)), -1) for t in est["time_s"]])
keep = (pick >= 0) & (est["received"] == 1)
truth = {k: v[pick[keep]] for k, v in truth.items()}
est = {k: v[keep] for k, v in est.items()}
err_a = np.abs(est["alpha_deg"] - est["alpha_true_deg"])
err_b = np.abs(est["beta_deg"] - est["beta_true_deg"])
sig_a, sig_b = est["sigma_alpha_deg"], est["sigma_beta_deg"]
gust = truth["gust_deg"]


def row(label, s):
    return (f"| {label} | {s.sum()} | {err_a[s].mean():.3f} | {np.median(sig_a[s]):.3f} | "
            f"{100 * np.mean(err_a[s] <= 2 * sig_a[s]):.1f} % | {err_b[s].mean():.3f} | "
            f"{np.median(sig_b[s]):.3f} | {100 * np.mean(err_b[s] <= 2 * sig_b[s]):.1f} % |")


head = "| frames | α MAE | α median 1σ | α within 2σ | β MAE | β median 1σ | β within 2σ |"
print(f"{len(err_a)} frames of {sys.argv[1]}\n")
print("| all " + head + "\n|---|---|---|---|---|---|---|---|")
print(row("all", np.ones(len(err_a), bool)))
for name, x, edges in [
    ("airspeed, m/s", truth["vt_mps"], [0, 35, 40, 50, 60, 70, 1e9]),
    ("flap, °", truth["tef_deg"], [-1e9, 1, 15, 25, 1e9]),
    ("α, °", truth["alpha_deg"], [-1e9, 0, 3, 6, 9, 1e9]),
    ("vertical gust angle, °", gust, [0, 0.5, 1, 2, 3, 5, 1e9]),
    ("time, s", truth["time_s"], list(range(0, int(truth["time_s"].max()) + 100, 100))),
]:
    print(f"\n| {name} " + head + "\n|---|---|---|---|---|---|---|---|")
    for a, b in zip(edges[:-1], edges[1:]):
        s = (x >= a) & (x < b)
        if s.sum() >= 50:
            label = f"{a:g}–{b:g}".replace("-1e+09–", "< ").replace("–1e+09", " +")
            print(row(label, s))
