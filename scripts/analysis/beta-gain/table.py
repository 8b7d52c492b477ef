#!/usr/bin/env python3
"""The page of scripts/analysis/beta-gain/run.sh: WORK COMMAND NAME... (NAME `stock` is JSBSim's
F-16; every other NAME a development variant of airframes/f16-variants/, by its spec's `name`).
Reads WORK/rows.csv
(`trainer fit-sigma --rows`) and WORK/filter-NAME.json (`trainer eval-filter --json`), the flights'
own CSVs for the true β; writes WORK/bars.json (for `trainer bars`) and prints the page."""

import collections
import csv
import datetime
import json
import os
import platform
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from airframe_spec import named_variants  # noqa: E402


def side_change(spec):
    """The scale of the side force's sideslip terms over the model's (None: the model's own): the
    SIDE axis times CYb's own scale (offsets, and the surface and rate terms' scales, are not in it)."""
    if spec is None:
        return 1.0
    axis = spec.get("axes", {}).get("SIDE", 1.0)
    return axis * spec.get("coefficients", {}).get("aero/coefficient/CYb", {}).get("scale", 1.0)


def card_order(flight):
    """A test flight's place on the card (test_KIND_NN) and its short name."""
    parts = flight.split("_")
    return int(parts[-1]) if parts[-1].isdigit() else 0, "_".join(parts[1:-1]) or flight


def gain(truth, err):
    """Least-squares slope of the error over the truth (with an intercept), and the error left when
    that line is taken out."""
    slope, icept = np.polyfit(truth, err, 1)
    return slope, err - slope * truth - icept


def nan(v):
    """A gain the filter could not measure (no spread in the truth), null in its JSON, as NaN."""
    return float("nan") if v is None else v


def main():
    work, command, names = sys.argv[1], sys.argv[2], sys.argv[3:]
    specs = {n: spec for n, _, spec in named_variants("f16")}
    unknown = [n for n in names if n != "stock" and n not in specs]
    if unknown:
        sys.exit(f"beta-gain: no airframes/f16-variants/*.toml is named {', '.join(unknown)}")
    flights = collections.defaultdict(lambda: ([], [], []))
    with open(os.path.join(work, "rows.csv")) as f:
        for r in csv.DictReader(f):
            if r["angle"] == "beta":
                frames, errs, sigmas = flights[(r["dataset"], r["flight"])]
                frames.append(int(r["frame"]))
                errs.append(float(r["err_mdeg"]) / 1000.0)
                sigmas.append(float(r["sigma_mdeg"]) / 1000.0)
    lines = ["# β on an airframe whose side force is not the model's: a gain error", "",
             f"Command: `{command}`  ",
             f"Machine: {platform.machine()}, {os.cpu_count()} cores, {datetime.date.today()}; the shipped estimator (int8, deployed).", "",
             "The four test flights of the `paper` preset (seed 1) on JSBSim's F-16 and on each development",
             "variant. *Gain error*: the slope of the β error over the true β, least squares over every frame of",
             "the four flights (−5 % reads a true 4° as 3.8°); per flight in brackets, in the card's order.",
             "*MAE without it*: the β MAE left with that line (slope and offset, fitted on these same frames)",
             "taken out, about what a right gain would give (a little less). *Within 2σ*: the share of frames",
             "whose β error is within twice the 1σ the estimator reports, as flown and with that line taken out",
             "(the 1σ unchanged). *Filter's own gain error*: the",
             "same slope of the air-data filter's β alone (`trainer eval-filter`), which the β network reads.",
             "*Filter's side-force scale*: what the filter learned by the end of each flight (mean, range), beside",
             "the variant's own scale of the side force's sideslip terms (its SIDE axis times its CYβ scale).", "",
             "| aircraft flown | side force's sideslip terms | β MAE | gain error | MAE without it | within 2σ: as flown / without it | filter's own gain error | filter's side-force scale |",
             "|---|---|---|---|---|---|---|---|"]
    bars = []
    worst = model_fslope = None
    for name in names:
        ds = f"out/sigma/test/{name}"
        truths, errs, sigmas, per = [], [], [], []
        for (d, fl), (frames, e, sg) in sorted(flights.items(), key=lambda kv: card_order(kv[0][1])):
            if d != ds:
                continue
            with open(os.path.join(ROOT, d, f"{fl}.csv")) as f:
                beta = [float(r["beta_deg"]) for r in csv.DictReader(f)]
            t = np.array([beta[i] for i in frames])
            e = np.array(e)
            per.append((card_order(fl)[1], gain(t, e)[0]))
            truths.append(t)
            errs.append(e)
            sigmas.append(np.array(sg))
        if not truths:
            sys.exit(f"beta-gain: no rows of {ds} in {work}/rows.csv")
        t, e, sg = np.concatenate(truths), np.concatenate(errs), np.concatenate(sigmas)
        slope, rest = gain(t, e)
        left = float(np.mean(np.abs(rest)))
        cover, cover_left = (100 * float(np.mean(np.abs(x) <= 2 * sg)) for x in (e, rest))
        with open(os.path.join(work, f"filter-{name}.json")) as f:
            filt = json.load(f)
        # A flight whose filter ended unhealthy has no scale (null).
        ky = [fl["final_side_scale"] for fl in filt["flags"] if fl.get("final_side_scale") is not None]
        fper = sorted((card_order(fl["flight"]), nan(fl["beta_gain_error"])) for fl in filt["flags"])
        fslope = nan(filt["beta_gain_error"])
        sb = side_change(specs.get(name))
        label = "JSBSim's F-16 (the model)" if name == "stock" else name
        learnt = f"{np.mean(ky):.3f} ({min(ky):.3f}–{max(ky):.3f})" if ky else "–"
        lines.append(f"| {label} | × {sb:.3g} | {np.mean(np.abs(e)):.3f} | **{100 * slope:+.1f} %** "
                     f"({', '.join(f'{k} {100 * s:+.1f}' for k, s in per)}) | {left:.3f} | {cover:.1f} / {cover_left:.1f} % | {100 * fslope:+.1f} % "
                     f"({', '.join(f'{k} {100 * s:+.1f}' for (_, k), s in fper)}) | {learnt} |")
        bars.append([label, [100 * slope, 100 * fslope, 100 * (sb - 1), 100 * (np.mean(ky) - 1) if ky else float("nan")]])
        if name == "stock":
            model_fslope = fslope
        if worst is None or abs(slope) > abs(worst[1]):
            worst = (label, slope, float(np.mean(np.abs(e))), left, fslope, cover, cover_left)
    lines += ["", f"The largest gain error is {worst[0]}'s ({100 * worst[1]:+.1f} %): its β MAE would be about "
              f"{worst[3]:.3f}° instead of {worst[2]:.3f}° with it taken out, and {worst[6]:.1f} % of its frames "
              f"instead of {worst[5]:.1f} % would lie within the 2σ it reports. The filter's own β is off by "
              f"{100 * worst[4]:+.1f} % there"
              + (f" ({100 * model_fslope:+.1f} % on JSBSim's F-16)" if model_fslope is not None else "") + ".", "",
              "![β gain error against the side-force change](beta-gain.png)"]
    lines.append("")
    print("\n".join(lines))
    spec = {"series": ["β gain error of the shipped estimator", "β gain error of the filter alone",
                       "the airframe's sideslip side-force change",
                       "the filter's side-force scale − 1"],
            "panels": [{"title": "β gain error against the side-force change, %", "xlabel": "%", "rows": bars}]}
    with open(os.path.join(work, "bars.json"), "w") as f:
        json.dump(spec, f)


if __name__ == "__main__":
    main()
