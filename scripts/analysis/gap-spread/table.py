#!/usr/bin/env python3
"""The gap-spread page (scripts/analysis/gap-spread/run.sh): per development variant and test
seed, the int8 α/β MAE of the matched, uncalibrated and shipped (in-service) estimators, the share
of the uncalibrated-to-matched gap the shipped one closes, and its share of frames within 2σ, then the same
pooled over every seed's flights (frame-weighted). Reads WORK/eval/EST-SEED-VARIANT.json
(`trainer eval --json`); writes WORK/bars.json (for `trainer bars`) and prints the page.

    table.py WORK COMMAND "SEEDS" VARIANT..."""

import datetime
import json
import math
import os
import platform
import sys


def load(work, est, seed, name):
    path = os.path.join(work, "eval", f"{est}-{seed}-{name}.json")
    try:
        with open(path) as f:
            e = json.load(f)
    except (OSError, json.JSONDecodeError) as err:
        sys.exit(f"gap-spread: cannot read {path} ({err}): re-run scripts/analysis/gap-spread/run.sh")
    out = {"silent": sum(c["silent"] for c in e["flagged"])}
    for a in ("alpha", "beta"):
        out[a] = e[a]["overall"]["mae"]
        out[a + "_n"] = e[a]["overall"]["n"]
        # The share within 2σ is of the frames with a known 1σ.
        out[a + "_2s"] = e["sigma"][a]["within_2sigma"]
        out[a + "_2s_n"] = e["sigma"][a]["frames"]
    return out


def pool(rows):
    """Frame-weighted means over several seeds' figures, each over its own frames; silent frames summed."""
    out = {"silent": sum(r["silent"] for r in rows)}
    for k in ("alpha", "beta", "alpha_2s", "beta_2s"):
        n = sum(r[k + "_n"] for r in rows)
        out[k + "_n"] = n
        out[k] = sum(r[k] * r[k + "_n"] for r in rows) / n if n else float("nan")
    return out


def closed(u, s, m):
    """The share of the gap from the uncalibrated u to the matched m that s closes, as the
    calibration table computes it (NaN: no gap)."""
    return (u - s) / (u - m) if u != m else float("nan")


def pct(x):
    return "–" if x != x else f"{100 * x:.0f} %"


def main():
    work, command, seeds, names = sys.argv[1], sys.argv[2], sys.argv[3].split(), sys.argv[4:]
    lines = ["# How firm the calibration table's gap closed is: the same estimators on more test flights", "",
             f"Command: `{command}`  ",
             f"Machine: {platform.machine()}, {os.cpu_count()} cores, {datetime.date.today()}.", "",
             "The table of [calibration.md](calibration.md) scores every estimator on the four test flights of",
             "the `paper` preset with seed 1 flown on each development variant. Here the same estimators, as",
             "`scripts/calibration-accuracy` built them (nothing trained or fitted again), are scored on the",
             f"`paper` test flights of seeds {', '.join(seeds)} flown on the same variant directories: int8 α / β MAE",
             "in degrees, the deployed estimator with its flags. *Matched*: trained on the variant;",
             "*uncalibrated*: the same recipe trained on JSBSim's F-16; *in service*: the shipped estimator.",
             "*Gap closed*: (uncalibrated − in service) / (uncalibrated − matched). *Within 2σ*: the shipped",
             "estimator's frames whose error is within twice its 1σ. *Pooled*: every seed's flights together",
             "(frame-weighted), the figure with the least noise. Silent frames: the shipped estimator's (every",
             "flag clear, α off by more than 2° or β by more than 1°).", "",
             "| variant | seed | matched | uncalibrated | in service | gap closed α | gap closed β | within 2σ α / β | silent |",
             "|---|---|---|---|---|---|---|---|---|"]
    bars = {"alpha": [], "beta": []}
    summary = []
    for name in names:
        per = {s: {e: load(work, e, s, name) for e in ("matched", "uncalibrated", "shipped")} for s in seeds}
        per["pooled"] = {e: pool([per[s][e] for s in seeds]) for e in ("matched", "uncalibrated", "shipped")}
        gaps = {}
        for i, s in enumerate(seeds + ["pooled"]):
            m, u, sh = per[s]["matched"], per[s]["uncalibrated"], per[s]["shipped"]
            g = {a: closed(u[a], sh[a], m[a]) for a in ("alpha", "beta")}
            gaps[s] = g
            b = "**" if s == "pooled" else ""
            lines.append(f"| {name if i == 0 else ''} | {b}{s}{b} | {m['alpha']:.3f} / {m['beta']:.3f} | "
                         f"{u['alpha']:.3f} / {u['beta']:.3f} | {sh['alpha']:.3f} / {sh['beta']:.3f} | "
                         f"{b}{pct(g['alpha'])}{b} | {b}{pct(g['beta'])}{b} | "
                         f"{100 * sh['alpha_2s']:.1f} / {100 * sh['beta_2s']:.1f} % | {sh['silent']} |")
        lo, hi = {}, {}
        for a in ("alpha", "beta"):
            per_seed = [gaps[s][a] for s in seeds]
            # `trainer bars` reads numbers only: a seed without a gap draws no bar.
            bars[a].append([name, [0.0 if math.isnan(x) else 100 * x for x in per_seed + [gaps["pooled"][a]]]])
            known = [x for x in per_seed if not math.isnan(x)]
            lo[a], hi[a] = (min(known), max(known)) if known else (math.nan, math.nan)
        summary.append(f"{name} α {pct(lo['alpha'])}–{pct(hi['alpha'])} (pooled {pct(gaps['pooled']['alpha'])}), "
                       f"β {pct(lo['beta'])}–{pct(hi['beta'])} (pooled {pct(gaps['pooled']['beta'])})")
    lines += ["", "Gap closed over the seeds, lowest–highest: " + "; ".join(summary) + ".", "",
              "![Gap closed per seed and pooled](gap-spread.png)", ""]
    print("\n".join(lines))
    series = [f"seed {s}" for s in seeds] + ["pooled"]
    spec = {"series": series,
            "panels": [{"title": "α: gap closed by the shipped estimator, %",
                        "xlabel": "%", "rows": bars["alpha"]},
                       {"title": "β: gap closed by the shipped estimator, %",
                        "xlabel": "%", "rows": bars["beta"]}]}
    with open(os.path.join(work, "bars.json"), "w") as f:
        json.dump(spec, f)


if __name__ == "__main__":
    main()
