"""Shipped hybrid β MAE on every flight of the dataset vs profile, turbulence severity, role.
Needs: $WORK/run-<flight>/estimates.csv of all 68 flights (run_all.sh); no replay.
usage: nice -n 19 <repo>/.venv/bin/python g_by_flight.py > "$WORK/out/g_by_flight.md"
"""
import json, re
import numpy as np
from common import DATA, flights, mae, load_flight, load_estimates
from paths import VAL_FLIGHTS
VAL = open(VAL_FLIGHTS).read().split()
rows = []
for fl in flights():
    n = fl["name"]
    x = open(f"{DATA}/{n}.xml").read()
    sev = int(re.search(r'milspec/severity" value="(\d+)', x).group(1))
    e = load_estimates(n)
    d = load_flight(n)
    err = e["beta_deg"] - d["beta_deg"]
    role = "test" if fl["split"] == "test" else ("val" if n in VAL else "train")
    rows.append((fl["profile"], sev, role, n, mae(err), np.mean(np.abs(d["beta_deg"])), len(err)))
print("# Shipped hybrid β MAE per flight\n")
print("| profile | severity | role | flight | β MAE | mean abs β |")
print("|---|---|---|---|---|---|")
for r in sorted(rows):
    print(f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[4]:.3f} | {r[5]:.2f} |")
print("\n## Mean β MAE by profile × severity (frames-weighted; all roles; [n flights])\n")
profs = sorted({r[0] for r in rows})
sevs = sorted({r[1] for r in rows})
print("| profile | " + " | ".join(f"sev {s}" for s in sevs) + " |")
print("|---|" + "---|" * len(sevs))
for p in profs:
    cells = []
    for s in sevs:
        sel = [r for r in rows if r[0] == p and r[1] == s]
        cells.append(f"{sum(r[4]*r[6] for r in sel)/sum(r[6] for r in sel):.3f} [{len(sel)}]" if sel else "")
    print(f"| {p} | " + " | ".join(cells) + " |")
print("\n## Held-out only (validation + test flights)\n")
for r in sorted(rows):
    if r[2] != "train":
        print(f"- {r[3]} ({r[2]}, severity {r[1]}): β MAE {r[4]:.3f}")
