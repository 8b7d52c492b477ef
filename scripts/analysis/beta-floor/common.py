"""Shared helpers for the β error analysis (analysis only; nothing here is used by the project).

Computes nothing by itself: dataset I/O (with an .npz cache in $WORK/cache), the aircraft's geometry
and IMU lever arm ($AIRCRAFT: aircraft/<name>.toml and its JSBSim model), ISA, the slope of the body
lateral force in β from a replay's JSBSim terms (any aircraft), the F-16 side and drag coefficients
parsed from estimator-core/src/aero/f16_tables.rs (F-16 only), the memoryless β inversion of the
lateral force, the IMU's anti-alias filter at 120 Hz, MAE and a zero-phase band split.

Data: $DATA (hil-sim generate --preset large --seed 1; default <repo>/out/data/large), the
shipped estimator's per-frame answers in $WORK/run-<flight>/estimates.csv (run_all.sh). See paths.py.
"""
import csv
import json
import os
import re
import tomllib
import xml.etree.ElementTree as ET

import jsbsim
import numpy as np

from paths import AIRCRAFT, DATA, HERE, REPO, WORK  # noqa: F401 (re-exported)
FT = 0.3048
G0 = 9.80665
LB_KG = 0.45359237


# ---------------------------------------------------------------------------------------------
# The aircraft ($AIRCRAFT): its description aircraft/<name>.toml and its JSBSim model (the pinned
# package's aircraft/<model>/<model>.xml, which the dataset's scripts <use>).
def _aircraft():
    path = os.path.join(REPO, "aircraft", AIRCRAFT + ".toml")
    if not os.path.exists(path):
        raise SystemExit(f"AIRCRAFT={AIRCRAFT}: no {path}")
    with open(path, "rb") as f:
        desc = tomllib.load(f)
    model = desc["jsbsim"]["model"]
    xml = os.path.join(jsbsim.get_default_root_dir(), "aircraft", model, model + ".xml")
    return desc, xml, ET.parse(xml).getroot()


AIRCRAFT_DESC, AIRCRAFT_XML, _MODEL = _aircraft()
JSBSIM_MODEL = AIRCRAFT_DESC["jsbsim"]["model"]


def _metric(tag):
    """A <metrics> length (m) or area (m²) of the JSBSim model."""
    e = _MODEL.find("metrics/" + tag)
    unit = e.get("unit", "FT2" if tag == "wingarea" else "FT")
    v = float(e.text)
    return {"FT": v * FT, "FT2": v * FT * FT, "M": v, "M2": v}[unit]


S_M2 = _metric("wingarea")
B_M = _metric("wingspan")
C_M = _metric("chord")
EMPTY_KG = (AIRCRAFT_DESC["mass"]["empty_weight_lb"] + AIRCRAFT_DESC["mass"]["pilot_lb"]) * LB_KG
LEVER = np.array(AIRCRAFT_DESC["installation"]["imu_lever_arm_m"], dtype=float)


def manifest():
    with open(os.path.join(DATA, "manifest.json")) as f:
        m = json.load(f)
    flown = (m.get("aircraft") or {}).get("name")
    if flown is not None and flown != AIRCRAFT:
        raise SystemExit(f"{DATA} was flown on the {flown}, not AIRCRAFT={AIRCRAFT}: set AIRCRAFT={flown}")
    return m


def flights(split=None):
    m = manifest()
    return [fl for fl in m["flights"] if split is None or fl["split"] == split]


def load_csv(path):
    with open(path) as f:
        r = csv.reader(f)
        head = next(r)
        rows = np.array([[float(x) if x != "" else np.nan for x in row] for row in r])
    return {h: rows[:, i] for i, h in enumerate(head)}


_cache = {}


def load_flight(name):
    """Dataset columns of flight `name` as a dict of numpy arrays."""
    if name in _cache:
        return _cache[name]
    path = os.path.join(DATA, name + ".csv")
    npz = os.path.join(WORK, "cache", name + ".npz")
    if os.path.exists(npz) and os.path.getmtime(npz) > os.path.getmtime(path):
        d = dict(np.load(npz))
    else:
        d = load_csv(path)
        os.makedirs(os.path.dirname(npz), exist_ok=True)
        np.savez(npz, **d)
    _cache[name] = d
    return d


def load_estimates(name):
    path = os.path.join(WORK, "run-" + name, "estimates.csv")
    with open(path) as f:
        r = csv.DictReader(f)
        rows = list(r)
    e = {
        "seq": np.array([int(x["seq"]) for x in rows]),
        "time_s": np.array([float(x["time_s"]) for x in rows]),
        "received": np.array([int(x["received"]) for x in rows]),
        "beta_true_deg": np.array([float(x["beta_true_deg"]) for x in rows]),
        "alpha_true_deg": np.array([float(x["alpha_true_deg"]) for x in rows]),
    }
    def num(k, scale):
        return np.array([float(x[k]) * scale if x[k] != "" else np.nan for x in rows])
    e["alpha_deg"] = num("alpha_deg", 1.0)
    e["beta_deg"] = num("beta_deg", 1.0)
    e["v_aero_mps"] = num("v_aero_mps", 1.0)
    e["w_aero_mps"] = num("w_aero_mps", 1.0)
    # The flag bits back as one integer (estimates.csv has a 0/1 column per flag, in bit order).
    flag_cols = [k for k in rows[0] if k.startswith("flag_")] if rows else []
    e["flags"] = np.array([sum(1 << b for b, k in enumerate(flag_cols) if x[k] == "1")
                           if x["received"] == "1" else -1 for x in rows])
    return e


# ---------------------------------------------------------------------------------------------
# ISA, as estimator_core::filter::isa (geometric altitude → density, speed of sound)
def isa(alt_m):
    alt_m = np.asarray(alt_m, dtype=float)
    R_E, T0, P0, L, R, g = 6_356_766.0, 288.15, 101_325.0, -0.0065, 287.05287, 9.80665
    h = R_E * alt_m / (R_E + alt_m)
    t11 = T0 + L * 11_000.0
    expo = -g / (L * R)
    hc = np.minimum(h, 11_000.0)
    t = T0 + L * hc
    p = P0 * (t / T0) ** expo * np.exp(-g * np.maximum(h - 11_000.0, 0.0) / (R * t11))
    return p / (R * t), np.sqrt(1.4 * R * t)


# ---------------------------------------------------------------------------------------------
# The slope of the body-axis lateral aerodynamic force in β, from JSBSim's own terms (any aircraft
# whose aerodynamics are in wind axes: DRAG, SIDE, LIFT). F_y,body = Y·cosβ − D·sinβ (JSBSim's Tw2b),
# so ∂F_y,body/∂β = ∂Y/∂β·cosβ − Y·sinβ − D·cosβ − ∂D/∂β·sinβ ≈ ∂Y/∂β − D − β·∂D/∂β for small β.
# The terms that read β are each of degree 1 in it (β or |β| times factors free of β, or a table
# linear in β through 0: F-16 CYb, CYb_M; f15 CYb, CDbeta; c172p CYb for |β| < 0.349 rad, CDbeta),
# so a term's ∂/∂β is its value / β: exact, from the replay's recorded term values.
_BETA_PROPS = ("aero/beta-rad", "aero/mag-beta-rad", "aero/beta-deg", "aero/mag-beta-deg")


def _reads(fn, tags=("property", "independentVar")):
    """The properties a JSBSim function reads: its factors and, by default, its tables' indices."""
    return [(e.text or "").strip() for e in fn.iter() if e.tag in tags]


def _axis_functions(*axes):
    """(axis, function) for every aero/coefficient function of the model's `axes`."""
    for a in _MODEL.find("aerodynamics").findall("axis"):
        if a.get("name") in axes:
            for fn in a.findall("function"):
                yield a.get("name"), fn


def _helpers_reading(test):
    """The model's helper functions (aero/function/...) that read a property passing `test`: a term
    that reads one of them reads that property without naming it."""
    return {fn.get("name") for fn in _MODEL.find("aerodynamics").findall("function")
            if any(test(p) for p in _reads(fn))}


def beta_terms():
    """{'SIDE': [...], 'DRAG': [...]}: the model's aero/coefficient functions of those axes that read β."""
    axes = {a.get("name") for a in _MODEL.find("aerodynamics").findall("axis")}
    if not {"DRAG", "SIDE", "LIFT"} <= axes:
        raise SystemExit(f"{AIRCRAFT_XML}: aerodynamics not in wind axes ({sorted(axes)})")
    hidden = _helpers_reading(lambda p: "beta" in p)
    out = {"SIDE": [], "DRAG": []}
    for axis, fn in _axis_functions(*out):
        beta = [p for p in _reads(fn) if "beta" in p or p in hidden]
        if any(p not in _BETA_PROPS for p in beta):
            raise SystemExit(f"{AIRCRAFT_XML}: {fn.get('name')} reads {beta}: not a known degree-1 β term")
        if beta:
            out[axis].append(fn.get("name"))
    return out


# The side force's terms that read the aerodynamic body rates (JSBSim's velocities/p-aero-rad_sec and
# r-aero-rad_sec: the body rates less the turbulence's rotational rates, FGAuxiliary's vAeroPQR =
# vPQR − TurbPQR). A gyro measures the body rates, so the part of these terms that the rotational
# turbulence makes is a lateral force no sensor reads. Each term is of degree 1 in its rate (the
# rate times factors free of it: F-16 and c172p CYp, CYr; the f15's side force has none).
_RATE_PROPS = {"velocities/p-aero-rad_sec": "p", "velocities/r-aero-rad_sec": "r"}


def rate_terms():
    """{'p': [...], 'r': [...]}: the model's SIDE aero/coefficient functions that read each aero rate."""
    hidden = _helpers_reading(lambda p: p in _RATE_PROPS)
    out = {"p": [], "r": []}
    for _, fn in _axis_functions("SIDE"):
        props = _reads(fn)
        if any(p in hidden for p in props):
            raise SystemExit(f"{AIRCRAFT_XML}: {fn.get('name')} reads an aero rate through a helper function")
        rates = {_RATE_PROPS[p] for p in props if p in _RATE_PROPS}
        if len(rates) > 1:
            raise SystemExit(f"{AIRCRAFT_XML}: {fn.get('name')} reads both aero rates: not a degree-1 rate term")
        for rate in rates:
            out[rate].append(fn.get("name"))
    return out


def turbulence_side_force_lbs(r):
    """The lateral force (lbf) the rotational turbulence makes through the side force's rate terms, at
    every step of a replay `r`: each term's value per unit of its aero rate, times the aero rate less
    the body rate (`velocities/p-rad_sec`, relative to the Earth; the gyros read it plus the Earth's
    rate, 7e-5 rad/s). A step whose aero rate is near 0 takes its neighbours' value per rate."""
    out = np.zeros_like(r["aero__beta_rad"])
    for rate, terms in rate_terms().items():
        if not terms:
            continue
        aero = r[key(f"velocities/{rate}-aero-rad_sec")]
        body = r[key(f"velocities/{rate}-rad_sec")]
        s = sum(r[key(t)] for t in terms)
        out = out + per_unit(s, aero) * (aero - body)
    return out


def surface_terms():
    """[(term, property, column, factor)]: each SIDE aero/coefficient function that reads a surface the
    aircraft senses (its description's [surfaces]), the surface property the term reads, the dataset
    column of the sensed surface (degrees) and the factor from that column to the term's property
    (1/deg_per_unit, times π/180 or 180/π where the term reads the -rad twin of a sensed -deg property
    or the reverse). Each term reads one surface, to degree 1 (its value is the surface times factors
    free of it: F-16 CYDa, CYdr; f15 and c172p CYda, CYdr)."""
    sensed = {}
    for col, spec in (AIRCRAFT_DESC.get("surfaces") or {}).items():
        if not isinstance(spec, dict) or "property" not in spec:
            continue
        prop, per = spec["property"], float(spec.get("deg_per_unit", 1.0))
        sensed[prop] = (col, 1.0 / per)
        for a, b, c in (("-deg", "-rad", np.pi / 180.0), ("-rad", "-deg", 180.0 / np.pi)):
            if prop.endswith(a):
                sensed.setdefault(prop[: -len(a)] + b, (col, c / per))
    out = []
    for _, fn in _axis_functions("SIDE"):
        # factors only: a surface that indexes a table (the c172p's flap in CYb, CYp, CYr) is not a
        # degree-1 term of it, and its sensor's 0.02° moves such a term by nothing that counts
        hits = [p for p in dict.fromkeys(_reads(fn, ("property",))) if p in sensed]
        if len(hits) > 1:
            raise SystemExit(f"{AIRCRAFT_XML}: {fn.get('name')} reads two sensed surfaces {hits}")
        for p in hits:
            out.append((fn.get("name"), p, *sensed[p]))
    return out


def per_unit(value, x, floor=1e-4):
    """value / x at every step; where |x| ≤ floor, the neighbours' ratio (a term of degree 1 in x)."""
    ok = np.abs(x) > floor
    per = np.where(ok, value / np.where(ok, x, 1.0), np.nan)
    if not ok.any():
        # a surface or rate held at 0 all flight: its term's slope cannot be read from the replay
        raise SystemExit("per_unit: the variable never leaves 0; its term's slope is unknown")
    return np.interp(np.arange(len(per)), np.flatnonzero(ok), per[ok])


def key(prop):
    """A JSBSim property's key in a replay (replay120.py)."""
    return prop.replace("/", "__").replace("-", "_")


def beta_term_slopes(r):
    """(∂Y/∂β, ∂D/∂β), lbf per rad, at every step of a replay `r` (replay120.py)."""
    b = r["aero__beta_rad"]
    t = beta_terms()

    def per_beta(axis):  # β exactly 0: the neighbours' slope
        return per_unit(sum(r[key(p)] for p in t[axis]), b, floor=0.0) if t[axis] else np.zeros_like(b)
    return per_beta("SIDE"), per_beta("DRAG")


def side_force_slope_lbs(r):
    """∂F_y,body/∂β (lbf per rad, small β) at every step of a replay `r` (replay120.py)."""
    dy, dd = beta_term_slopes(r)
    return dy - r["forces__fwx_aero_lbs"] - r["aero__beta_rad"] * dd


# ---------------------------------------------------------------------------------------------
# The F-16 side and drag coefficients, parsed from estimator-core/src/aero/f16_tables.rs (read
# only). JSBSim FGTable semantics: 1-D linear between breakpoints, end values held; 2-D: row first.
# F-16 only: every function from here to beta_from_cy_body.
_TABLES = None


def _parse_tables():
    global _TABLES
    if _TABLES is not None:
        return _TABLES
    if AIRCRAFT != "f16":
        raise SystemExit(f"AIRCRAFT={AIRCRAFT}: common.py's side and drag tables are the F-16's")
    src = open(os.path.join(REPO, "estimator-core", "src", "aero", "f16_tables.rs")).read()
    t = {}
    for m in re.finditer(r"pub static (\w+): Table1<\d+> = Table1 \{\s*key: Var::(\w+),\s*x: \[([^\]]*)\],\s*y: \[([^\]]*)\]", src):
        x = np.array([float(v) for v in m.group(3).split(",") if v.strip()])
        y = np.array([float(v) for v in m.group(4).split(",") if v.strip()])
        t[m.group(1)] = (x, y)
    for m in re.finditer(r"pub static (\w+): Table2<\d+, \d+> = Table2 \{\s*row: Var::(\w+),\s*col: Var::(\w+),\s*rows: \[([^\]]*)\],\s*cols: \[([^\]]*)\],\s*data: \[(.*?)\n    \],", src, re.S):
        rows = np.array([float(v) for v in m.group(4).split(",") if v.strip()])
        cols = np.array([float(v) for v in m.group(5).split(",") if v.strip()])
        data = []
        for line in m.group(6).strip().splitlines():
            line = line.split("//")[0].strip().strip(",").strip("[]")
            if line:
                data.append([float(v) for v in line.split(",") if v.strip()])
        t[m.group(1)] = (rows, cols, np.array(data))
    _TABLES = t
    return t


def tab1(name, key):
    x, y = _parse_tables()[name]
    return np.interp(key, x, y)  # holds end values, linear inside: as FGTable


def tab2(name, r, c):
    rows, cols, data = _parse_tables()[name]
    r = np.asarray(r, float)
    c = np.asarray(c, float)
    i = np.clip(np.searchsorted(rows, r, side="left"), 1, len(rows) - 1)
    j = np.clip(np.searchsorted(cols, c, side="left"), 1, len(cols) - 1)
    rf = np.clip((r - rows[i - 1]) / (rows[i] - rows[i - 1]), 0, 1)
    cf = np.clip((c - cols[j - 1]) / (cols[j] - cols[j - 1]), 0, 1)
    lo = data[i - 1, j - 1] + cf * (data[i - 1, j] - data[i - 1, j - 1])
    hi = data[i, j - 1] + cf * (data[i, j] - data[i, j - 1])
    return lo + rf * (hi - lo)


def side_parts(alpha_rad, mach, aileron_rad, rudder_rad, p_rps, r_rps, tas_mps):
    """CY (wind axes) = slope·β + rest: returns (slope per rad, rest)."""
    bi2vel = B_M / (2.0 * tas_mps)
    slope = -1.146 + tab1("CYB_M", mach)
    rest = (-0.0226 * aileron_rad + 0.086 * rudder_rad
            + bi2vel * p_rps * tab1("CYP", alpha_rad) + bi2vel * r_rps * tab1("CYR", alpha_rad))
    return slope, rest


def lef_schedule_rad(alpha_rad, mach):
    """f16.xml's leading-edge flap in flight with the gear down, as the plant flies: its 25° above
    15° α needs the gear up, so 15° above 5° α, −2° above Mach 0.9, else 0."""
    return np.where(alpha_rad > 0.0873, 0.262, np.where(mach > 0.9, -0.0349, 0.0))


def drag_coef(alpha_rad, mach, elevator_rad, lef_rad, speedbrake_rad, flap_mix_rad, q_rps, tas_mps):
    ci2vel = C_M / (2.0 * tas_mps)
    return (tab2("CDDH", alpha_rad, elevator_rad) + tab1("CDMACH", mach)
            + lef_rad * tab1("CDDLEF", alpha_rad) + flap_mix_rad * 0.08
            + speedbrake_rad * tab1("CDDSB", alpha_rad)
            + q_rps * ci2vel * tab1("CDQ", alpha_rad)
            + q_rps * ci2vel * lef_rad * tab1("CDQ_DLEF", alpha_rad))


def beta_from_cy_body(cy_body, alpha_rad, mach, aileron_rad, rudder_rad, p_rps, r_rps, tas_mps, cd):
    """Solve CY_body = Y(β)·cosβ − D·sinβ for β (Newton, 3 iterations; D held)."""
    slope, rest = side_parts(alpha_rad, mach, aileron_rad, rudder_rad, p_rps, r_rps, tas_mps)
    b = (cy_body - rest) / (slope - cd)
    for _ in range(3):
        y = slope * b + rest
        f = y * np.cos(b) - cd * np.sin(b) - cy_body
        df = slope * np.cos(b) - y * np.sin(b) - cd * np.cos(b)
        b = b - f / df
    return b


# ---------------------------------------------------------------------------------------------
# The IMU's anti-alias path (hil_sim::sensors): 3 ms first-order lag (the unit's, per 120 Hz step)
# then the flight computer's 2nd-order Butterworth at 6 Hz. Applied to a 120 Hz signal.
def imu_lag_120(x, lag_tau=0.003):
    """The IMU unit's lag alone: its 120 Hz outputs (the dataset's `*_sub*` columns) of `x`."""
    a = 1.0 - np.exp(-(1.0 / 120.0) / lag_tau)
    y = np.empty_like(x)
    s = x[0]
    for i, v in enumerate(x):
        s = s + a * (v - s)
        y[i] = s
    return y


def butter_120(y, fc=6.0):
    """The flight computer's biquad alone, primed on the first input (hil_sim's Biquad)."""
    k = np.tan(np.pi * fc / 120.0)
    q = 1 / np.sqrt(2)
    norm = 1 / (1 + k / q + k * k)
    b0 = k * k * norm
    b = [b0, 2 * b0, b0]
    aa = [2 * (k * k - 1) * norm, (1 - k / q + k * k) * norm]
    out = np.empty_like(y)
    x1 = x2 = y1 = y2 = y[0]
    for i, v in enumerate(y):
        o = b[0] * v + b[1] * x1 + b[2] * x2 - aa[0] * y1 - aa[1] * y2
        x2, x1 = x1, v
        y2, y1 = y1, o
        out[i] = o
    return out


def imu_filter_120(x, lag_tau=0.003, fc=6.0):
    return butter_120(imu_lag_120(x, lag_tau), fc)


def upsample_120(t20, x20):
    """Linear interpolation of a 20 Hz series onto the 120 Hz grid (6 steps per frame)."""
    t120 = np.arange(t20[0] - 5 / 120.0, t20[-1] + 1e-9, 1 / 120.0)
    return t120, np.interp(t120, t20, x20)


def mae(x):
    x = np.asarray(x)
    x = x[np.isfinite(x)]
    return float(np.mean(np.abs(x))) if len(x) else float("nan")


def butter_lowpass_zero_phase(x, fc, fs=20.0):
    """Zero-phase 2nd-order Butterworth (forward-backward), for splitting an error into bands."""
    k = np.tan(np.pi * fc / fs)
    q = 1 / np.sqrt(2)
    norm = 1 / (1 + k / q + k * k)
    b0 = k * k * norm
    b = [b0, 2 * b0, b0]
    a = [2 * (k * k - 1) * norm, (1 - k / q + k * k) * norm]

    def run(v):
        out = np.empty_like(v)
        x1 = x2 = y1 = y2 = v[0]
        for i, s in enumerate(v):
            o = b[0] * s + b[1] * x1 + b[2] * x2 - a[0] * y1 - a[1] * y2
            x2, x1 = x1, s
            y2, y1 = y1, o
            out[i] = o
        return out
    return run(run(x)[::-1])[::-1]
