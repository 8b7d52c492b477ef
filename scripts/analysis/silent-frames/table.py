"""Where the shipped estimator's silent frames are: by dynamic pressure and gust angle, and each run
of them.

For every test flight of the datasets given, the estimator's frames (`hil-sim run --firmware host`,
WORK/runs/DATASET/FLIGHT/estimates.csv) beside the flight's own truth: the dynamic pressure and the
gust angle (the true α less the α of the velocity over the ground less the wind's 30-s centred mean:
scripts/analysis/alpha-wind). *Silent*: every flag clear, α off by more than 2° or β by more than
1° (`trainer eval`'s count). Writes WORK/silent-frames.md and WORK/bars.json (for `trainer bars`).

usage: .venv/bin/python scripts/analysis/silent-frames/table.py WORK COMMAND SEED DIR ...
"""
import datetime
import json
import os
import platform
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "alpha-wind"))
from table import columns, flags_clear, gust_alpha_deg, read  # noqa: E402

SILENT_ALPHA_DEG = 2.0
SILENT_BETA_DEG = 1.0
# Slow flight: the stall approaches of the high-α profile fly below it (1.7-3 kPa).
SLOW_PA = 3000.0
# A gust angle beyond it: the air moves α by more than the estimate's typical error.
GUST_DEG = 1.0
# Silent frames this close (frames) are one run.
RUN_GAP = 10
REGIMES = [("q̄ ≥ 3 kPa, gust angle ≤ 1°", False, False), ("q̄ ≥ 3 kPa, gust angle > 1°", False, True),
           ("q̄ < 3 kPa, gust angle ≤ 1°", True, False), ("q̄ < 3 kPa, gust angle > 1°", True, True)]
# The plot's labels (its font draws no q̄).
LABELS = ["≥ 3 kPa, gust ≤ 1°", "≥ 3 kPa, gust > 1°", "< 3 kPa, gust ≤ 1°", "< 3 kPa, gust > 1°"]


def flight_frames(work, d, csv_name):
    flight = csv_name[:-4]
    est = read(os.path.join(work, "runs", os.path.relpath(d, work), flight, "estimates.csv"))
    t, a_true, a_est, b_true, b_est, s_a, received = columns(
        est, ["time_s", "alpha_true_deg", "alpha_deg", "beta_true_deg", "beta_deg", "sigma_alpha_deg", "received"])
    flown = read(os.path.join(d, csv_name))
    g = gust_alpha_deg(flown)
    (q,) = columns(flown, ["qbar_pa"])
    n = min(len(g), len(a_true))
    num = lambda c: np.array([x if x else "nan" for x in c[:n]], dtype=float)  # noqa: E731
    ea, eb = num(a_est) - num(a_true), num(b_est) - num(b_true)
    ok = (np.array(received[:n]) == "1") & np.isfinite(ea) & np.isfinite(eb)
    clear = flags_clear(est)[:n]
    silent = ok & clear & ((np.abs(ea) > SILENT_ALPHA_DEG) | (np.abs(eb) > SILENT_BETA_DEG))
    return dict(t=num(t), ea=ea, eb=eb, ok=ok, silent=silent, q=np.array(q[:n], dtype=float), g=g[:n],
                truth=num(a_true), sigma=num(s_a))


def runs(mask):
    """(first, last) index of each run of True in `mask`, runs closer than RUN_GAP joined."""
    idx = np.flatnonzero(mask)
    out = []
    for i in idx:
        if out and i - out[-1][1] <= RUN_GAP:
            out[-1][1] = i
        else:
            out.append([i, i])
    return out


def main():
    work, command, seed, dirs = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
    flights = []
    for d in dirs:
        for csv_name in sorted(os.listdir(d)):
            if csv_name.startswith("test_") and csv_name.endswith(".csv"):
                f = flight_frames(work, d, csv_name)
                f["name"] = os.path.relpath(os.path.join(d, csv_name[:-4]), work)
                flights.append(f)
    cat = {k: np.concatenate([f[k][f["ok"]] for f in flights]) for k in ("ea", "q", "g", "silent")}
    n_all = len(cat["ea"])
    lines = ["# Where the silent frames are", "",
             f"Command: `{command}`  ",
             f"Machine: {platform.machine()}, {os.cpu_count()} cores, {datetime.date.today()}; the shipped "
             "estimator of this build, each flight stepped through it on the host.", "",
             f"The `paper` preset's test cards with seed {seed} on JSBSim's F-16 and on each development "
             f"variant, and on 12 randomised airframes of seed {seed}: {len(flights)} flights, {n_all:,} "
             "frames, none of which any choice of the shipped estimator saw. *Silent*: every flag clear, "
             f"α off by more than {SILENT_ALPHA_DEG:.0f}° or β by more than {SILENT_BETA_DEG:.0f}°. "
             "*Gust angle*: the true α less the α of the velocity over the ground less the wind's 30-s "
             "centred mean, in the body's x-z plane: the part of α that the EGI's velocity and attitude do "
             "not give, which only the normal force carries (simulator truth, for this sorting only). "
             "*Share missed*: the least-squares slope of the α error on the gust angle, negated (1: the "
             "estimate misses all of it).", "",
             "![α off by more than 2° and silent frames, by regime](silent-frames.png)", "",
             "| regime | frames | share of the frames | α MAE | share missed | frames α off > 2° | their share | silent frames |",
             "|---|---|---|---|---|---|---|---|"]
    bars, silent_bars = [], []
    for (label, slow, gust), short in zip(REGIMES, LABELS):
        m = ((cat["q"] < SLOW_PA) == slow) & ((np.abs(cat["g"]) > GUST_DEG) == gust)
        e, g = cat["ea"][m], cat["g"][m]
        big = int((np.abs(e) > SILENT_ALPHA_DEG).sum())
        missed = -float(np.polyfit(g, e, 1)[0]) if m.sum() > 2 else float("nan")
        lines.append(f"| {label} | {m.sum():,} | {m.sum() / n_all:.1%} | {np.abs(e).mean():.3f} | "
                     f"{missed:.2f} | {big:,} | {big / max(m.sum(), 1):.2%} | {int(cat['silent'][m].sum())} |")
        bars.append([short, [100.0 * big / max(m.sum(), 1)]])
        silent_bars.append([short, [float(cat["silent"][m].sum())]])
    lines += ["", "Each run of silent frames (frames within half a second joined): the flight, when, the true "
              "α and the dynamic pressure, the gust angle, and over its silent frames the α error, the estimate's α 1σ and the β error:", "",
              "| flight | time, s | frames | true α | q̄, kPa | gust angle | α error | α 1σ | β error |",
              "|---|---|---|---|---|---|---|---|---|"]
    rng = lambda x, fmt: f"{fmt.format(np.nanmin(x))} … {fmt.format(np.nanmax(x))}"  # noqa: E731
    for f in flights:
        for a, b in runs(f["silent"]):
            s = slice(a, b + 1)
            sil = f["silent"][s]
            lines.append(f"| {f['name']} | {f['t'][a]:.1f}–{f['t'][b]:.1f} | {int(sil.sum())} | "
                         f"{rng(f['truth'][s], '{:.1f}')}° | {rng(f['q'][s] / 1000, '{:.1f}')} | "
                         f"{rng(f['g'][s], '{:+.1f}')}° | {rng(f['ea'][s][sil], '{:+.1f}')}° | "
                         f"{rng(f['sigma'][s][sil], '{:.2f}')}° | {rng(f['eb'][s][sil], '{:+.1f}')}° |")
    lines.append("")
    page = "\n".join(lines)
    with open(os.path.join(work, "silent-frames.md"), "w") as f:
        f.write(page)
    spec = {"series": ["the shipped estimator"],
            "panels": [{"title": f"α off by more than 2°: {len(flights)} held-out flights (seed {seed})",
                        "xlabel": "% of the frames of each regime (dynamic pressure, gust angle)", "rows": bars},
                       {"title": "silent frames (every flag clear, α off > 2° or β off > 1°)",
                        "xlabel": "frames", "rows": silent_bars}]}
    with open(os.path.join(work, "bars.json"), "w") as f:
        json.dump(spec, f)
    print(page)


if __name__ == "__main__":
    main()
