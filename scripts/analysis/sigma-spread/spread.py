"""Each dataset's share of errors within 2σ under one common factor on an angle's weights:
spread.py AIRCRAFT FIT_ROWS TEST_ROWS PAGE BARS_JSON COMMAND (run.sh). The rows are `trainer
fit-sigma --rows` CSVs; PAGE is the markdown written, BARS_JSON the `trainer bars` spec of its
plot (sigma-spread.png beside the page), COMMAND the line the page says made it."""
import array
import collections
import datetime
import json
import os
import platform
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from airframe_spec import description  # noqa: E402

FACTORS = [0.9, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5]
# The factors searched for the minimax and for a band that holds every fitting dataset.
GRID = np.round(np.arange(0.80, 2.001, 0.01), 2)
ANGLES = ("alpha", "beta")
SYMBOL = {"alpha": "α", "beta": "β"}


def rows(path):
    """{(dataset, angle): (|error|, 1σ)} in millidegrees."""
    acc = collections.defaultdict(lambda: (array.array("d"), array.array("d")))
    with open(path) as f:
        head = f.readline().rstrip("\n").split(",")
        if head[:4] != ["dataset", "flight", "frame", "angle"] or head[-2:] != ["sigma_mdeg", "err_mdeg"]:
            sys.exit(f"spread.py: {path} is not a `trainer fit-sigma --rows` CSV of this version")
        for line in f:
            ds, _, _, angle, rest = line.split(",", 4)
            s, e = rest.rsplit(",", 2)[1:]
            a = acc[(ds, angle)]
            a[0].append(abs(float(e)))
            a[1].append(float(s))
    return {k: (np.frombuffer(e), np.frombuffer(s)) for k, (e, s) in acc.items()}


def within(data, f):
    e, s = data
    return float(np.mean(e <= 2.0 * f * s))


def minimax(fit, angle):
    """The factor whose worst fitting dataset is nearest to 95 % within 2σ."""
    sets = [v for (ds, a), v in fit.items() if a == angle]
    dev = [max(abs(within(v, f) - 0.95) for v in sets) for f in GRID]
    return float(GRID[int(np.argmin(dev))])


def label(ds, title):
    base = os.path.basename(ds)
    return (f"the model, {title}" if title else "the model") if base == "stock" else base


def main():
    if len(sys.argv) != 7:
        sys.exit(__doc__)
    aircraft, fit_path, test_path, page, bars, command = sys.argv[1:7]
    fit, test = rows(fit_path), rows(test_path)
    for path, data in ((fit_path, fit), (test_path, test)):
        missing = [a for a in ANGLES if not any(ang == a for _, ang in data)]
        if missing:
            sys.exit(f"spread.py: {path} holds no {' or '.join(missing)} rows (remake it: delete it and rerun run.sh)")
    title = description(aircraft).get("title", aircraft)
    name = lambda ds: label(ds, title)  # noqa: E731
    fitting = sorted({ds for ds, _ in fit})
    tested = list(dict.fromkeys(ds for ds, _ in test))
    pct = lambda x: f"{100 * x:.1f}"  # noqa: E731
    best = {a: minimax(fit, a) for a in ANGLES}
    md = ["# The 1σ airframe by airframe", "",
          f"Command: `{command}`  ",
          f"Machine: {platform.machine()}, {os.cpu_count()} cores, {datetime.date.today()}.", "",
          f"The shipped estimator of the {title} has its 1σ fitted on {len(fitting)} datasets pooled (the `--data` of",
          f"its fit's command, `estimator-core/src/model/{aircraft}/sigma.rs`):",
          "one common factor per angle puts 95 % of all their frames within 2σ. A user flies one airframe.",
          "Here each dataset on its own, with every weight of an angle multiplied by a factor (1: as",
          "shipped), in % of its frames within 2σ; the target is 95 ± 3 % on every airframe. The 1σ is",
          "each frame's as the estimator reports it (millidegrees), times the factor.", "",
          "![% of frames outside 2σ, as shipped and with the minimax factor](sigma-spread.png)", ""]
    for a in ANGLES:
        sym = SYMBOL[a]
        md += [f"## {sym}", "", "The test flights (" + ", ".join(f"`{ds}`" for ds in tested) + "):", "",
               "| aircraft flown | " + " | ".join(f"× {f:g}" for f in FACTORS) + " |",
               "|---|" + "---|" * len(FACTORS)]
        for (ds, ang), v in test.items():
            if ang == a:
                md.append(f"| {name(ds)} | " + " | ".join(pct(within(v, f)) for f in FACTORS) + " |")
        sets = {ds: v for (ds, ang), v in fit.items() if ang == a}
        md += ["", f"The {len(sets)} fitting datasets:", "",
               "| | " + " | ".join(f"× {f:g}" for f in FACTORS) + " |", "|---|" + "---|" * len(FACTORS)]
        cov = {f: sorted(within(v, f) for v in sets.values()) for f in FACTORS}
        md.append("| lowest | " + " | ".join(pct(cov[f][0]) for f in FACTORS) + " |")
        md.append("| median | " + " | ".join(pct(cov[f][len(sets) // 2]) for f in FACTORS) + " |")
        md.append("| highest | " + " | ".join(pct(cov[f][-1]) for f in FACTORS) + " |")
        md.append("| below 92 / above 98 | " + " | ".join(
            f"{sum(c < 0.92 for c in cov[f])} / {sum(c > 0.98 for c in cov[f])}" for f in FACTORS) + " |")
        lo = min(sets, key=lambda d: within(sets[d], 1.0))
        banded = [f for f in GRID if all(0.92 <= within(v, f) <= 0.98 for v in sets.values())]
        md += ["", f"The factor that brings the fitting dataset farthest from 95 % nearest to it: **× {best[a]:.2f}** "
               f"(its lowest {pct(min(within(v, best[a]) for v in sets.values()))} %, highest "
               f"{pct(max(within(v, best[a]) for v in sets.values()))} %); the lowest as shipped is `{lo}`. "
               + (f"Factors that put every fitting dataset within 92–98 %: × {banded[0]:.2f}–{banded[-1]:.2f}."
                  if banded else "No factor from × 0.80 to × 2.00 puts every fitting dataset within 92–98 %."), ""]
    with open(page, "w") as f:
        f.write("\n".join(md) + "\n")
    panels = []
    for a in ANGLES:
        sets = [v for (ds, ang), v in fit.items() if ang == a]
        out = lambda v, f: 100 * (1 - within(v, f))  # noqa: E731
        r = [[label(ds, ""), [out(v, 1.0), out(v, best[a])]] for (ds, ang), v in test.items() if ang == a]
        r.append(["fitting dataset, most", [max(out(v, 1.0) for v in sets), max(out(v, best[a]) for v in sets)]])
        r.append(["fitting dataset, fewest", [min(out(v, 1.0) for v in sets), min(out(v, best[a]) for v in sets)]])
        panels.append({"title": f"{SYMBOL[a]}: % of frames outside 2σ (target 5 ± 3)", "xlabel": "% of frames", "rows": r})
    spec = {"series": ["as shipped (× 1)", f"× the minimax factor (α {best['alpha']:.2f}, β {best['beta']:.2f})"], "panels": panels}
    with open(bars, "w") as f:
        json.dump(spec, f)


if __name__ == "__main__":
    main()
