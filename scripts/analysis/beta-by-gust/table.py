"""β error against the turbulence each flight flew, for several aircraft: is an aircraft's β harder
because of its airframe or because the same gust is a larger angle at its airspeed?

For every test flight of the datasets given: the Milspec severity its script set, its gust angle
(the RMS of the wind's turbulent part, every axis, over the mean true airspeed: the angle a gust
of that size makes) and the shipped estimator's α and β MAE (from `trainer eval --json`, written
beside the dataset as DIR.eval.json). Prints Markdown: one table by severity, one by gust angle,
and one of the estimate's 1σ and flags over the same flights, per aircraft.

usage: .venv/bin/python scripts/analysis/beta-by-gust/table.py NAME=DIR[,DIR...] ...
"""
import csv
import json
import math
import os
import re
import sys

import numpy as np

# The turbulent part of the wind: what a 30 s centred moving mean does not explain (the steady wind
# and its slow changes, and the 1-cosine gusts' slow part, stay in the mean).
WINDOW_S, HZ = 30.0, 20


def sigma_row(name, dirs):
    """Per aircraft: the share of α and β errors within 2σ, `UNCERTAIN` frames, and the silent
    frames (every flag clear, α off by more than 2° or β by more than 1°) with the flights that
    hold them."""
    frames = frames_b = within_a = within_b = uncertain = silent = 0
    holders = []
    for d in dirs:
        ev = json.load(open(d.rstrip("/") + ".eval.json"))
        k, kb = ev["sigma"]["alpha"]["frames"], ev["sigma"]["beta"]["frames"]
        frames += k
        frames_b += kb
        within_a += ev["sigma"]["alpha"]["within_2sigma"] * k
        within_b += ev["sigma"]["beta"]["within_2sigma"] * kb
        for f in ev["flagged"]:
            uncertain += f["uncertain"]
            silent += f["silent"]
            if f["silent"]:
                holders.append(f"{os.path.basename(d.rstrip('/'))}/{f['flight']} {f['silent']}")
    return (f"| {name} | {frames} | {100 * within_a / frames:.1f} % | {100 * within_b / frames_b:.1f} % | "
            f"{100 * uncertain / frames:.1f} % | {silent} | {', '.join(holders) or '–'} |")


def flight_rows(name, d):
    ev = json.load(open(d.rstrip("/") + ".eval.json"))
    alpha, beta = dict(ev["alpha"]["per_flight"]), dict(ev["beta"]["per_flight"])
    for fl in sorted(beta):
        script = open(os.path.join(d, fl + ".xml")).read()
        m = re.search(r'milspec/severity" value="(\d+)"', script)
        sev = int(m.group(1)) if m else 0
        rows = list(csv.DictReader(open(os.path.join(d, fl + ".csv"))))
        wind = np.array([[float(r[f"wind_{k}_mps"]) for k in ("north", "east", "down")] for r in rows])
        vt = np.array([float(r["vt_mps"]) for r in rows])
        n = int(WINDOW_S * HZ)
        kernel = np.ones(n) / n
        slow = np.stack([np.convolve(wind[:, i], kernel, mode="same") for i in range(3)], 1)
        inner = slice(n // 2, len(rows) - n // 2)
        gust = wind[inner] - slow[inner]
        sigma = math.sqrt(float(np.mean(np.sum(gust**2, 1)) / 3.0))
        angle = math.degrees(sigma / float(np.mean(vt)))
        yield dict(aircraft=name, flight=fl, severity=sev, sigma_mps=sigma, vt=float(np.mean(vt)),
                   gust_deg=angle, alpha=alpha[fl]["mae"], beta=beta[fl]["mae"])


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    rows = []
    names = []
    sigma = []
    for arg in sys.argv[1:]:
        name, _, dirs = arg.partition("=")
        if not dirs:
            sys.exit(f"beta-by-gust: {arg!r} must be NAME=DIR[,DIR...]")
        names.append(name)
        for d in dirs.split(","):
            rows += list(flight_rows(name, d))
        sigma.append(sigma_row(name, dirs.split(",")))

    def table(title, key, bins, label):
        print(f"### {title}\n")
        head = " | ".join(f"{n} flights | {n} α | {n} β" for n in names)
        print(f"| {label} | {head} |")
        print("|---|" + "---|---|---|" * len(names))
        for lo, hi, text in bins:
            cells = []
            for n in names:
                sel = [r for r in rows if r["aircraft"] == n and lo <= key(r) < hi]
                if sel:
                    cells.append(f"{len(sel)} | {np.mean([r['alpha'] for r in sel]):.3f} | "
                                 f"{np.mean([r['beta'] for r in sel]):.3f}")
                else:
                    cells.append("0 | – | –")
            print(f"| {text} | " + " | ".join(cells) + " |")
        print()

    print(f"{len(rows)} test flights; MAE in degrees, the mean over the flights of each bin.\n")
    table("By Milspec severity (the same gust speeds for every aircraft)", lambda r: r["severity"],
          [(s, s + 1, str(s)) for s in range(8)], "severity")
    edges = [0.0, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0]
    table("By gust angle (RMS turbulent wind ÷ true airspeed)", lambda r: r["gust_deg"],
          [(a, b, f"{a:g}–{b:g}°") for a, b in zip(edges, edges[1:])], "gust angle")
    for n in names:
        sel = [r for r in rows if r["aircraft"] == n]
        print(f"- {n}: mean true airspeed {np.mean([r['vt'] for r in sel]):.0f} m/s, "
              f"gust RMS {np.mean([r['sigma_mps'] for r in sel]):.2f} m/s")
    print("\n### The 1σ and the flags on the same flights\n")
    print("| aircraft | frames | α within 2σ | β within 2σ | `UNCERTAIN` | silent frames | flights with silent frames |")
    print("|---|---|---|---|---|---|---|")
    print("\n".join(sigma))


if __name__ == "__main__":
    main()
