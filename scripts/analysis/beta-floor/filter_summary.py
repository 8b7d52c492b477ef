"""Summarise $WORK/filter/*.json (filter_tune.sh: trainer eval-filter --split train, one constant
changed at a time): β MAE overall, aggressive flights, severity ≥5 flights, calm (severity ≤2)
flights, α overall. Standard library only.
usage: python3 filter_summary.py > "$WORK/out/filter_tune.md"
"""
import glob, json, os, re
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
print("# Filter alone on the 54 training flights (trainer eval-filter --split train), β MAE, deg\n")
print("| --tune | overall | aggressive | severity ≥ 5 | severity ≤ 2 | α overall |")
print("|---|---|---|---|---|---|")
for f in sorted(glob.glob(os.path.join(WORK, "filter", "*.json")), key=lambda p: (os.path.basename(p) != "base.json", p)):
    j = json.load(open(f))
    per = j["beta"]["per_flight"]
    cells = [f"{j['beta']['overall']['mae']:.3f}"]
    for sel in (lambda n: prof[n] == "aggressive", lambda n: sev[n] >= 5, lambda n: sev[n] <= 2):
        v, k = agg(per, sel)
        cells.append(f"{v:.3f} [{k}]")
    print(f"| `{j['tune'] or '(shipped F16_CONFIG)'}` | " + " | ".join(cells) + f" | {j['alpha']['overall']['mae']:.3f} |")
