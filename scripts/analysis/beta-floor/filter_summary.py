"""Summarise `trainer eval-filter --json` results: β MAE overall, aggressive flights, severity ≥ 5,
severity 3–4 and calm (severity ≤ 2) flights (frame-weighted, severity from each flight's runscript
in $DATA), α overall. Standard library only.
usage: python3 filter_summary.py [F.json ...] > table.md
       (no arguments: $WORK/filter/*.json, written by filter_tune.sh: the training split, one
       constant changed at a time)
"""
import glob, json, os, re, sys
from paths import DATA, WORK
sev = {}
prof = {}
for x in glob.glob(DATA + "/*_init.xml"):
    n = os.path.basename(x)[:-9]
    sev[n] = int(re.search(r'milspec/severity" value="(\d+)', open(f"{DATA}/{n}.xml").read()).group(1))
    prof[n] = n.split("_")[1]
def agg(per, sel):
    rows = [(m["n"], m["mae"]) for n, m in per if sel(n)]
    return sum(a * b for a, b in rows) / sum(a for a, _ in rows), len(rows)
files = sys.argv[1:] or sorted(glob.glob(os.path.join(WORK, "filter", "*.json")),
                               key=lambda p: (os.path.basename(p) != "base.json", p))
print("# Filter alone (trainer eval-filter), β MAE, deg; [flights]\n")
print("| --tune | split | overall | aggressive | severity ≥ 5 | severity 3–4 | severity ≤ 2 | α overall |")
print("|---|---|---|---|---|---|---|---|")
for f in files:
    j = json.load(open(f))
    per = j["beta"]["per_flight"]
    cells = [f"{j['beta']['overall']['mae']:.3f}"]
    for sel in (lambda n: prof[n] == "aggressive", lambda n: sev[n] >= 5, lambda n: 3 <= sev[n] <= 4,
                lambda n: sev[n] <= 2):
        v, k = agg(per, sel)
        cells.append(f"{v:.3f} [{k}]")
    print(f"| `{j['tune'] or '(shipped filter::CONFIG)'}` | {j['split']} | " + " | ".join(cells)
          + f" | {j['alpha']['overall']['mae']:.3f} |")
