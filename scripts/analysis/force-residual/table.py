"""What the normal force shows: the force model at the true air-data point, and the share of the
air-data filter's α error that the normal force carries, by dynamic pressure.

Reads WORK/frames/NAME.csv (`trainer eval-filter --frames`, one per aircraft), the flights' own CSVs
(WORK/cards/NAME/, for the wind) and the shipped estimator's frames (WORK/runs/NAME/FLIGHT/
estimates.csv). *The α the force shows*: the normal specific force measured less the model's at the
filter's point, over the model's ∂f_z/∂α there: the α change that would close the gap; its *share*
is that over the filter's α error (1: the force shows all of the error, 0: none). Writes
WORK/force-residual.md, WORK/lines.json and WORK/force-residual.png (through `trainer lines`, the
binary in $TRAINER).

usage: TRAINER=target/release/trainer .venv/bin/python scripts/analysis/force-residual/table.py WORK COMMAND SEED NAME ...
"""
import datetime
import json
import os
import platform
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "alpha-wind"))
from table import columns, read  # noqa: E402

# Slow flight: the stall approaches of the high-α profile fly below it (1.7-3 kPa).
SLOW_PA = 3000.0
# The filter's α error bands, degrees.
BANDS = [(0.0, 0.5), (0.5, 1.0), (1.0, 2.0), (2.0, 90.0)]
# α bands of the model check, degrees.
ALPHA_BANDS = [(-90.0, 5.0), (5.0, 15.0), (15.0, 20.0), (20.0, 90.0)]
# A miss: the filter's α off by more than this for at least MISS_FRAMES frames in slow flight.
MISS_DEG = 1.5
MISS_FRAMES = 5
DT = 0.05


def load(work, name):
    t = read(os.path.join(work, "frames", f"{name}.csv"))
    head, rows = t
    out = {"flight": np.array([r[0] for r in rows])}
    for k in head[1:]:
        out[k] = np.array(columns(t, [k])[0], dtype=float)
    out["err"] = out["alpha_filter_deg"] - out["alpha_true_deg"]
    out["shows"] = (out["fz_measured_mps2"] - out["fz_model_filter_mps2"]) / out["dfz_dalpha_filter_mps2_per_deg"]
    return out


def estimate_alpha(work, name, flight, n):
    est = read(os.path.join(work, "runs", name, flight, "estimates.csv"))
    (a,) = columns(est, ["alpha_deg"])
    a = np.array([x if x else "nan" for x in a], dtype=float)
    return np.concatenate([a, np.full(max(0, n - len(a)), np.nan)])[:n]


def model_table(d):
    """The model at the true point: residual by flight and α band."""
    lines = ["| flight | true α | frames | residual mean, m/s² | residual 1σ, m/s² | median ∂f_z/∂α, m/s² per ° | the 1σ as α |",
             "|---|---|---|---|---|---|---|"]
    r = d["fz_measured_mps2"] - d["fz_model_true_mps2"]
    for fl in dict.fromkeys(d["flight"]):
        for lo, hi in ALPHA_BANDS:
            k = (d["flight"] == fl) & (d["alpha_true_deg"] >= lo) & (d["alpha_true_deg"] < hi) & np.isfinite(r)
            if k.sum() < 20:
                continue
            slope = np.nanmedian(np.abs(d["dfz_dalpha_filter_mps2_per_deg"][k]))
            band = f"< {hi:.0f}°" if lo < -80 else (f"≥ {lo:.0f}°" if hi > 80 else f"{lo:.0f}–{hi:.0f}°")
            lines.append(f"| {fl} | {band} | {k.sum():,} | {r[k].mean():+.3f} | {r[k].std():.3f} | {slope:.2f} | "
                         f"{r[k].std() / slope:.2f}° |")
    return lines


def shows_table(sets):
    """What the force shows of the filter's α error, by dynamic pressure and error size."""
    lines = ["| aircraft | q̄ | filter's α error | frames | median error | median α the force shows | median share |",
             "|---|---|---|---|---|---|---|"]
    for label, d in sets:
        ok = np.isfinite(d["shows"]) & np.isfinite(d["err"])
        for slow in (True, False):
            q = d["qbar_pa"] < SLOW_PA if slow else d["qbar_pa"] >= SLOW_PA
            for lo, hi in BANDS:
                k = ok & q & (np.abs(d["err"]) >= lo) & (np.abs(d["err"]) < hi)
                if not k.any():
                    continue
                # Signed: +1 when the force asks for exactly the α that closes the error.
                nz = k & (d["err"] != 0)
                share = np.median(d["shows"][nz] / -d["err"][nz])
                band = f"> {lo:.0f}°" if hi > 80 else f"{lo:g}–{hi:g}°"
                lines.append(f"| {label} | {'< 3 kPa' if slow else '≥ 3 kPa'} | {band} | {k.sum():,} | "
                             f"{np.median(np.abs(d['err'][k])):.2f}° | {np.median(np.abs(d['shows'][k])):.2f}° | {share:+.2f} |")
    return lines


def misses(d):
    """Runs of at least MISS_FRAMES slow-flight frames with the filter's α off by more than MISS_DEG:
    (flight, index of its first frame, first and last index of the run), indices into `d`."""
    out = []
    for fl in dict.fromkeys(d["flight"]):
        idx = np.flatnonzero(d["flight"] == fl)
        bad = (np.abs(d["err"][idx]) > MISS_DEG) & (d["qbar_pa"][idx] < SLOW_PA)
        # Where a run of bad frames starts and ends (+1/-1 steps of the padded mask).
        edges = np.flatnonzero(np.diff(np.concatenate([[0], bad.astype(int), [0]])))
        for i, j in zip(edges[0::2], edges[1::2]):
            if j - i >= MISS_FRAMES:
                out.append((fl, idx[0], idx[i], idx[j - 1]))
    return out


def miss_row(work, d, name, fl, start, i, j):
    """One miss: what the gust did to α and q̄ from a second before it to its worst frame, and what
    the normal force did meanwhile."""
    k = i + int(np.argmax(np.abs(d["err"][i:j + 1])))
    b = max(i - int(1.0 / DT), start)
    flown = read(os.path.join(work, "cards", name, f"{fl}.csv"))
    wn, we, wd = (np.array(c, dtype=float) for c in columns(flown, ["wind_north_mps", "wind_east_mps", "wind_down_mps"]))
    dw = [w[k - start] - w[b - start] for w in (wn, we, wd)]
    est = estimate_alpha(work, name, fl, int((d["flight"] == fl).sum()))
    fz = d["fz_measured_mps2"]
    da = d["alpha_true_deg"][k] - d["alpha_true_deg"][b]
    dq = 100 * (d["qbar_pa"][k] / d["qbar_pa"][b] - 1)
    slope = d["dfz_dalpha_filter_mps2_per_deg"][b]
    return (f"| {name} | {fl} | {(i - start) * DT:.1f}–{(j - start) * DT:.1f} | {d['alpha_true_deg'][b]:.1f} → "
            f"{d['alpha_true_deg'][k]:.1f}° | {d['qbar_pa'][b] / 1000:.2f} → {d['qbar_pa'][k] / 1000:.2f} ({dq:+.0f} %) | "
            f"{dw[0]:+.1f}, {dw[1]:+.1f}, {dw[2]:+.1f} | {fz[k] - fz[b]:+.2f} ({slope * da:+.2f}) | "
            f"{d['err'][k]:+.2f}° | {est[k - start] - d['alpha_true_deg'][k]:+.2f}° | {d['shows'][k]:+.2f}° |"), (k, b)


def plot_spec(work, d, name, fl, start, k):
    lo, hi = max(start, k - int(4 / DT)), min(k + int(4 / DT), int(np.flatnonzero(d["flight"] == fl)[-1]))
    t = (np.arange(lo, hi + 1) - start) * DT
    est = estimate_alpha(work, name, fl, int((d["flight"] == fl).sum()))[lo - start:hi - start + 1]

    def pts(y):
        return [[float(a), float(b)] for a, b in zip(t, y) if np.isfinite(b)]

    s = slice(lo, hi + 1)
    return {"panels": [
        {"title": f"α, {fl} ({name})", "xlabel": "time, s", "ylabel": "α, deg", "series": [
            {"name": "true α", "points": pts(d["alpha_true_deg"][s])},
            {"name": "filter's α", "points": pts(d["alpha_filter_deg"][s])},
            {"name": "shipped estimate's α", "points": pts(est)}]},
        {"title": "dynamic pressure", "xlabel": "time, s", "ylabel": "kPa", "series": [
            {"name": "true dynamic pressure", "points": pts(d["qbar_pa"][s] / 1000)}]},
        {"title": "normal specific force at the CG", "xlabel": "time, s", "ylabel": "f_z, m/s²", "series": [
            {"name": "measured (IMU)", "points": pts(d["fz_measured_mps2"][s])},
            {"name": "model at the true point", "points": pts(d["fz_model_true_mps2"][s])},
            {"name": "model at the filter's point", "points": pts(d["fz_model_filter_mps2"][s])}]},
    ]}


def main():
    work, command, seed, names = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
    data = {n: load(work, n) for n in names}
    stock = data[names[0]]
    pooled = {k: np.concatenate([data[n][k] for n in names]) for k in stock}
    rows, worst = [], None
    for n in names:
        for fl, start, i, j in misses(data[n]):
            row, (k, _) = miss_row(work, data[n], n, fl, start, i, j)
            rows.append(row)
            e = abs(data[n]["err"][k])
            if n == names[0] and (worst is None or e > worst[0]):
                worst = (e, fl, start, k)
    machine = f"{platform.machine()}, {os.cpu_count()} cores, {datetime.date.today().isoformat()}"
    page = [
        "# What the normal force shows",
        "",
        f"Command: `{command}`  ",
        f"Machine: {machine}; the filter alone (`trainer eval-filter --data DIR --frames FILE`) and the shipped estimator "
        "(`hil-sim run --firmware host`) on each flight.",
        "",
        f"The `paper` preset's test cards with seed {seed} on JSBSim's F-16 ({names[0]}) and on the development variants "
        f"({', '.join(names[1:])}). For every frame, the body-z specific force the IMU measures (moved to the CG, as the "
        "filter moves it) beside the one the air-data filter's force model gives at the flight's true air-data point "
        "(JSBSim's α, β, Mach, airspeed, dynamic pressure, mass and body rates) and at the filter's own estimate (its "
        "α, β and airspeed, ISA density, the fuel gauge's mass, its lift scale). *The α the force shows*: the measured "
        "force less the model's at the filter's point, over ∂f_z/∂α there; its *share* of the filter's α error is "
        "+1 when the force asks for just the α that closes the error, 0 when the force is content with the wrong α.",
        "",
        "## The model at the true air-data point, JSBSim's F-16",
        "",
        "Measured less modelled normal force. The model is the plant's own here, so what is left comes from the "
        "measurement: the truth sampled at the frame's instant against the IMU's force through its 6 Hz anti-alias "
        "filter (most in turbulence: the aggressive card flies Milspec severity 4), the lever-arm correction, the "
        "surfaces as sensed (not separated here). *The 1σ as α*: the residual's 1σ over the median |∂f_z/∂α| of the "
        "band.",
        "",
        *model_table(stock),
        "",
        "## How much of the filter's α error the normal force shows",
        "",
        *shows_table([(names[0], stock), (f"all {len(names)}", pooled)]),
        "",
        "## The slow-flight misses",
        "",
        f"Each run of at least {MISS_FRAMES} frames below {SLOW_PA / 1000:.0f} kPa with the filter's α off by more than "
        f"{MISS_DEG}°: from a second before the run to its worst frame, the true α and q̄, the wind's change (north, "
        "east, down, m/s), the measured normal force's change (in brackets, the change the α change "
        "alone would have made at the first frame's q̄), and at the worst frame the filter's and the shipped "
        "estimate's α error and the α the force shows.",
        "",
        "| aircraft | flight | time, s | true α | q̄, kPa | wind change N, E, D | Δf_z measured (α alone), m/s² | filter's α error | estimate's α error | α the force shows |",
        "|---|---|---|---|---|---|---|---|---|---|",
        *(rows or ["| none | | | | | | | | | |"]),
        "",
    ]
    if worst is not None:
        _, fl, start, k = worst
        with open(os.path.join(work, "lines.json"), "w") as f:
            json.dump(plot_spec(work, stock, names[0], fl, start, k), f)
        subprocess.run([os.environ["TRAINER"], "lines", "--spec", os.path.join(work, "lines.json"),
                        "--out", os.path.join(work, "force-residual.png")], check=True)
        at = page.index("## The model at the true air-data point, JSBSim's F-16")
        page[at:at] = [f"![The largest slow-flight miss on {names[0]}: α, q̄ and the normal force]"
                       "(force-residual.png)", ""]
    with open(os.path.join(work, "force-residual.md"), "w") as f:
        f.write("\n".join(page))


if __name__ == "__main__":
    main()
