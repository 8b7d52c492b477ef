"""The table of scripts/analysis/lift-offset-egi/run.sh: per flight-test seed, the identified lift
offset ΔC_L and lift scale (± 1σ) with the EGI as recorded and as the truth, and their means.

    table.py MODE/SEED=CALIBRATION_JSON ...
"""

import json
import sys


def main():
    fits = {}
    for arg in sys.argv[1:]:
        key, path = arg.split("=", 1)
        mode, seed = key.split("/")
        sc = json.load(open(path))["scales"]
        fits.setdefault(mode, {})[seed] = (sc["offset"], sc["lift"])
    modes = list(fits)
    label = {"recorded": "EGI as recorded", "truth-egi": "EGI the truth"}
    seeds = list(fits[modes[0]])
    print("| flight-test seed | " + " | ".join(f"ΔC_L, {label.get(m, m)} | lift scale, {label.get(m, m)}" for m in modes) + " |")
    print("|---|" + "---|---|" * len(modes))
    for s in seeds:
        cells = []
        for m in modes:
            o, lift = fits[m][s]
            cells += [f"{o['value']:+.4f} ± {o['std_error']:.4f}", f"{lift['value']:.4f} ± {lift['std_error']:.4f}"]
        print(f"| {s} | " + " | ".join(cells) + " |")
    cells = []
    for m in modes:
        o = [fits[m][s][0]["value"] for s in seeds]
        lift = [fits[m][s][1]["value"] for s in seeds]
        cells += [f"mean {sum(o) / len(o):+.4f}", f"mean {sum(lift) / len(lift):.4f}"]
    print("| all | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
