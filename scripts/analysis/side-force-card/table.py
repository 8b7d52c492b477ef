#!/usr/bin/env python3
"""The side-force table of scripts/analysis/side-force-card/run.sh:

    table.py OUT COMMAND NAME=SPEC...

reads OUT/first/NAME/calibration.json (over the model cards) and OUT/final/NAME/calibration.json
(over the second card) and each airframe's spec (scripts/airframe-variant's TOML) for its truth,
prints the page and writes OUT/bars.json for `trainer bars`."""

import datetime
import json
import os
import platform
import sys
import tomllib


def truth(spec_path):
    """k_β (SIDE × CYb), the aileron's, the rudder's and the rate terms' scales of a spec."""
    with open(spec_path, "rb") as f:
        spec = tomllib.load(f)
    side = spec.get("axes", {}).get("SIDE", 1.0)
    c = spec.get("coefficients", {})
    term = lambda t: c.get(f"aero/coefficient/{t}", {}).get("scale", 1.0)  # noqa: E731
    return {"beta": side * term("CYb"), "aileron": side * term("CYDa"), "rudder": side * term("CYdr"), "rates": side}


def scales(path):
    with open(path) as f:
        s = json.load(f)["scales"]
    return {"beta": s["sideslip"], "controls": s["side_controls"]}


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    out, command, pairs = sys.argv[1], sys.argv[2], sys.argv[3:]
    rows, sums = [], {k: [0.0, 0.0] for k in ("beta", "rudder", "aileron", "rates")}
    bars = {"series": ["over the model cards", "over the second card"],
            "panels": [{"title": "sideslip terms: k_β − truth", "xlabel": "error", "rows": []},
                       {"title": "surface and rate terms: k_Y − the rudder's scale", "xlabel": "error", "rows": []}]}
    for pair in pairs:
        name, spec = pair.split("=", 1)
        t = truth(spec)
        first = scales(os.path.join(out, "first", name, "calibration.json"))
        final = scales(os.path.join(out, "final", name, "calibration.json"))
        e = lambda s: f"{s['value']:.3f} ± {s['std_error']:.3f}"  # noqa: E731
        rows.append(f"| {name} | {t['beta']:.3f} | {e(first['beta'])} | **{e(final['beta'])}** | "
                    f"{t['rudder']:.3f} / {t['aileron']:.3f} / {t['rates']:.3f} | {e(first['controls'])} | **{e(final['controls'])}** |")
        for j, s in enumerate((first, final)):
            sums["beta"][j] += abs(s["beta"]["value"] - t["beta"])
            for k in ("rudder", "aileron", "rates"):
                sums[k][j] += abs(s["controls"]["value"] - t[k])
        bars["panels"][0]["rows"].append([name, [first["beta"]["value"] - t["beta"], final["beta"]["value"] - t["beta"]]])
        bars["panels"][1]["rows"].append([name, [first["controls"]["value"] - t["rudder"], final["controls"]["value"] - t["rudder"]]])
    with open(os.path.join(out, "bars.json"), "w") as f:
        json.dump(bars, f)
    s = lambda k: f"{sums[k][0]:.3f} → {sums[k][1]:.3f}"  # noqa: E731
    print("\n".join([
        "# The side force over the model cards and over the second card", "",
        f"Command: `{command}`  ",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores, {datetime.date.today()}.", "",
        "Each airframe's flight test (sensor seed 1) identified by `trainer calibrate` over eight model cards (seeds 2–9), "
        "then over the same card flown on that identification's calibrated aircraft (seeds 2–9: the second card, "
        "docs/calibration.md, Method step 5), as `scripts/calibrate` does. k_β scales the side force's sideslip terms, "
        "k_Y its aileron, rudder and rate terms together; the truth is the airframe's spec (k_β: SIDE × CYb).", "",
        "| airframe | k_β truth | k_β over the model cards | k_β over the second card | truth: rudder / aileron / rate terms | k_Y over the model cards | k_Y over the second card |",
        "|---|---|---|---|---|---|---|", *rows, "",
        f"Summed |error|, over the model cards → over the second card: k_β {s('beta')}; k_Y against the rudder's scale "
        f"{s('rudder')}, the aileron's {s('aileron')}, the rate terms' {s('rates')}.", "",
        "![k_β and k_Y errors over the model cards and over the second card](side-force-card.png)", ""]))


if __name__ == "__main__":
    main()
