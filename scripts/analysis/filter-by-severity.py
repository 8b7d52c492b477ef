#!/usr/bin/env python3
"""The filter alone by turbulence severity (docs/filter.md, adaptive measurement noise).

Usage: trainer eval-filter --data DIR --split S [--tune KEYS] --json > F.json
       scripts/analysis/filter-by-severity.py DIR F.json

Prints the overall α and β MAE and the β MAE of the flights grouped by the MIL-spec turbulence
severity their runscript (DIR/<flight>.xml) sets: calm ≤ 2, 3–4, 5–6 (frame-weighted).
Standard library only.
"""
import json
import os
import re
import sys


def severity(data, flight):
    with open(os.path.join(data, flight + ".xml")) as f:
        m = re.search(r'turbulence/milspec/severity" value="([0-9.]+)"', f.read())
    return float(m.group(1)) if m else 0.0


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    data, path = sys.argv[1], sys.argv[2]
    with open(path) as f:
        r = json.load(f)
    groups = {"calm (sev <= 2)": [0.0, 0], "sev 3-4": [0.0, 0], "sev 5-6": [0.0, 0]}
    for flight, m in r["beta"]["per_flight"]:
        s = severity(data, flight)
        g = "calm (sev <= 2)" if s <= 2 else ("sev 3-4" if s <= 4 else "sev 5-6")
        groups[g][0] += m["mae"] * m["n"]
        groups[g][1] += m["n"]
    parts = [f"{k} {v[0] / v[1]:.3f}" for k, v in groups.items() if v[1]]
    print(f"tune '{r['tune']}' split {r['split']}: alpha {r['alpha']['overall']['mae']:.3f} "
          f"beta {r['beta']['overall']['mae']:.3f}; beta " + ", ".join(parts))


if __name__ == "__main__":
    main()
