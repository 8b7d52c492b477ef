"""Where the α error near the stall comes from: the gusts' vertical part, which no kinematic input
sees.

For every flight of the datasets given, the shipped estimator's frames (`hil-sim run --firmware
host`, its estimates.csv in OUT/DATASET/FLIGHT/) beside the flight's own truth. *Gust angle*: the
true α less the α of the velocity over the ground less the wind's 30-s centred mean, in the body's
x-z plane: the part of α the EGI's velocity and attitude do not give even with the steady wind
known, which only the normal force carries. *Share*: the least-squares slope of the α error on the
gust angle (−1: the estimate misses all of it; 0: none). Two tables: by band of true α over every
flight, and flight by flight over the frames above HIGH_ALPHA_DEG. Writes OUT/alpha-wind.md, the
bars' description OUT/bars.json (for `trainer bars`) and prints the page.

usage: .venv/bin/python scripts/analysis/alpha-wind/table.py NAME OUT COMMAND DIR ...
(NAME: the aircraft, for the plot's title)
"""
import csv
import datetime
import json
import math
import os
import platform
import re
import sys

import numpy as np

# The NED → body direction-cosine matrix per frame, as the filter's c_bn (one definition for the
# analysis scripts: scripts/analysis/kinematic-gate/replay.py).
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "kinematic-gate"))
from replay import body_from_ned  # noqa: E402

BANDS = [(-90.0, 5.0, "below 5°"), (5.0, 15.0, "5–15°"), (15.0, 20.0, "15–20°"),
         (20.0, 25.0, "20–25°"), (25.0, 90.0, "above 25°")]
HIGH_ALPHA_DEG = 15.0
SILENT_DEG = 2.0
# A band of fewer frames is in the table only: a few frames' large errors would set the plot's scale.
PLOT_MIN_FRAMES = 1000
# The wind's slow part, which the filter's wind estimate follows: a 30-s centred mean at 20 Hz
# (the turbulent part's definition of scripts/analysis/beta-by-gust).
MEAN_WIND_FRAMES = 600


def read(path):
    """A CSV's header and its rows (strings), read once."""
    with open(path, newline="") as f:
        rows = csv.reader(f)
        head = next(rows)
        return head, list(rows)


def columns(table, names):
    """The named columns of `read`'s (header, rows), each a list of strings."""
    head, rows = table
    idx = [head.index(n) for n in names]
    return [[r[i] for r in rows] for i in idx]


def flags_clear(table):
    """True where every flag of the frame is clear (the estimate's flag_* columns)."""
    head, rows = table
    idx = [i for i, n in enumerate(head) if n.startswith("flag_")]
    return np.array([all(r[i] == "0" for i in idx) for r in rows])


def moving_mean(x, frames):
    k = np.ones(frames) / frames
    return np.convolve(x, k, "same") / np.convolve(np.ones_like(x), k, "same")


def gust_alpha_deg(flight):
    """The gust angle, degrees, of every row of a flight's CSV as `read` gives it."""
    names = ["phi_deg", "theta_deg", "psi_deg", "v_north_mps", "v_east_mps", "v_down_mps",
             "wind_north_mps", "wind_east_mps", "wind_down_mps", "alpha_deg"]
    phi, th, psi, vn, ve, vd, wn, we, wd, alpha = (
        np.array(c, dtype=float) for c in columns(flight, names))
    v = np.stack([v - moving_mean(w, MEAN_WIND_FRAMES) for v, w in ((vn, wn), (ve, we), (vd, wd))], 1)
    c_bn = body_from_ned(np.radians(phi), np.radians(th), np.radians(psi))
    u, _, w = np.einsum("kij,kj->ik", c_bn, v)
    return alpha - np.degrees(np.arctan2(w, u))


def severity(script):
    found = re.findall(r'turbulence/milspec/severity" value="([0-9.]+)"', open(script).read())
    return found[0] if found else "–"


def cells(d, m):
    """The table cells every row shares, over the frames `m` of the frames `d`: count, α MAE, the
    median 1σ, the silent frames, the gust angle's RMS, the correlation and slope of the error on
    it and the MAE with that share taken out; and the MAE with and without the share, for a bar."""
    e, g = d["err"][m], d["gust"][m]
    slope = float(np.polyfit(g, e, 1)[0])
    corr = float(np.corrcoef(g, e)[0, 1])
    left = float(np.abs(e - slope * g).mean())
    silent = int(((np.abs(e) > SILENT_DEG) & d["clear"][m]).sum())
    mae = float(np.abs(e).mean())
    head = f"{m.sum():,} | {mae:.3f}"
    tail = (f"{np.median(d['sigma'][m]):.2f} | {silent} | {math.sqrt((g ** 2).mean()):.2f}° | "
            f"{corr:+.2f} | {slope:+.2f} | {left:.3f} |")
    return head, tail, [mae, left]


def main():
    aircraft, out, command, dirs = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
    flights = []
    for d in dirs:
        name = os.path.basename(d.rstrip("/"))
        for csv_name in sorted(os.listdir(d)):
            if not (csv_name.startswith("test_") and csv_name.endswith(".csv")):
                continue
            flight = csv_name[:-4]
            est = os.path.join(out, name, flight, "estimates.csv")
            table = read(est)
            a_true, a_est, s_a, received = columns(
                table, ["alpha_true_deg", "alpha_deg", "sigma_alpha_deg", "received"])
            g = gust_alpha_deg(read(os.path.join(d, csv_name)))
            n = min(len(g), len(a_true))
            a_est = np.array([x if x else "nan" for x in a_est[:n]], dtype=float)
            ok = (np.array(received[:n]) == "1") & np.isfinite(a_est)
            t = np.array(a_true[:n], dtype=float)
            flights.append(dict(
                name=f"{name}/{flight}", sev=severity(os.path.join(d, flight + ".xml")),
                err=(a_est - t)[ok], truth=t[ok], sigma=np.array(s_a[:n], dtype=float)[ok],
                clear=flags_clear(table)[:n][ok], gust=g[:n][ok]))
    cat = {k: np.concatenate([f[k] for f in flights]) for k in ("err", "truth", "sigma", "clear", "gust")}
    total = np.abs(cat["err"]).sum()
    lines = ["# α error and the gusts' vertical part, by α", "",
             f"Command: `{command}`  ",
             f"Machine: {platform.machine()}, {os.cpu_count()} cores, {datetime.date.today()}; the shipped "
             "estimator of this build, each flight stepped through it on the host by run.sh.", "",
             f"{len(flights)} flights, {len(cat['err']):,} frames. *Gust angle*: the true α less the α of the "
             "velocity over the ground less the wind's 30-s centred mean, in the body's x-z plane: the part "
             "of α that the EGI's velocity and attitude do not give even with the steady wind known; only "
             "the normal force carries it. *Share*: the least-squares slope of the α error on the gust angle "
             "(−1: the estimate misses all of it, 0: none). *Silent*: every flag clear, α off by more "
             f"than {SILENT_DEG:.0f}°.", "",
             "| true α | frames | α MAE | share of all α error | median 1σ | silent frames | gust angle, RMS | correlation | share | MAE without that share |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    bars = []
    for lo, hi, label in BANDS:
        m = (cat["truth"] >= lo) & (cat["truth"] < hi)
        if m.sum() < 20:
            continue
        head, tail, bar = cells(cat, m)
        share = np.abs(cat["err"][m]).sum() / total
        lines.append(f"| {label} | {head} | {share:.0%} | {tail}")
        if m.sum() >= PLOT_MIN_FRAMES:
            bars.append([label, bar])
    lines += ["", f"Flight by flight, the frames above {HIGH_ALPHA_DEG:.0f}° of true α (flights with at least "
              "200 such frames; *severity*: the Milspec severity its script sets):", "",
              "| flight | severity | frames | α MAE | median 1σ | silent frames | gust angle, RMS | correlation | share | MAE without that share |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for f in flights:
        m = f["truth"] > HIGH_ALPHA_DEG
        if m.sum() < 200:
            continue
        head, tail, _ = cells(f, m)
        lines.append(f"| {f['name']} | {f['sev']} | {head} | {tail}")
    lines.append("")
    page = "\n".join(lines)
    with open(os.path.join(out, "alpha-wind.md"), "w") as f:
        f.write(page)
    spec = {"series": ["the estimate", "the gust angle's share taken out"],
            "panels": [{"title": f"{aircraft}: α MAE by true α, {len(flights)} test flights (bands of {PLOT_MIN_FRAMES:,} frames or more)", "xlabel": "α MAE, degrees",
                        "rows": bars}]}
    with open(os.path.join(out, "bars.json"), "w") as f:
        json.dump(spec, f)
    print(page)


if __name__ == "__main__":
    main()
