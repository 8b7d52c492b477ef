"""What scripts/airframe-sensitivity, airframe-randomise and airframe-variant share: the aerodynamic
terms the randomiser draws and how widely, what a base model offers a variant (`base_model`: its
chord, terms and whether its engines are turbines), the named development variants, where JSBSim
finds an engine file, and a writer
of the scripts/airframe-variant specs they make (top-level scalars, then tables of scalars, lists
and inline tables)."""

import functools
import glob
import json
import os
import subprocess
import tomllib
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# The aircraft whose build is target/'s (scripts/lib/aircraft.sh's default_aircraft); another
# aircraft builds in target/NAME with ESTIMATOR_AIRCRAFT=NAME.
DEFAULT_AIRCRAFT = "f16"


def release_dir(name):
    """Aircraft NAME's release build, where its hil-sim and trainer are."""
    own = () if name == DEFAULT_AIRCRAFT else (name,)
    return os.path.join(ROOT, "target", *own, "release")


def aircraft_args(name):
    """What an aircraft's own hil-sim and trainer are told: `--aircraft NAME` but for the default."""
    return [] if name == DEFAULT_AIRCRAFT else ["--aircraft", name]


def build_env(name):
    """The environment a cargo command for aircraft NAME's build starts with ('' for the default)."""
    return "" if name == DEFAULT_AIRCRAFT else f"ESTIMATOR_AIRCRAFT={name} CARGO_TARGET_DIR=target/{name} "


# `scripts/airframe-randomise --terms`: each term times a factor uniform in 1 ± width·spread, drawn in
# this order (a seed's draws depend on it); SPREAD is its default spread.
SPREAD = 0.1
TERM_WIDTHS = (("CLDflaps", 2.0), ("CLDlef", 2.0), ("CYDa", 2.0), ("CYdr", 2.0), ("CYb", 1.0))


def description(name):
    """The aircraft description aircraft/NAME.toml, as a dict; refused unless it names its JSBSim
    model (`[jsbsim] model`)."""
    path = os.path.join(ROOT, "aircraft", name + ".toml")
    try:
        with open(path, "rb") as f:
            d = tomllib.load(f)
        if not isinstance(d["jsbsim"]["model"], str):
            raise TypeError("`[jsbsim] model` is not a name")
        return d
    except (OSError, tomllib.TOMLDecodeError, KeyError, TypeError) as e:
        known = " ".join(sorted(f[:-5] for f in os.listdir(os.path.join(ROOT, "aircraft")) if f.endswith(".toml")))
        raise SystemExit(f"no aircraft description {path} with a `[jsbsim] model` ({e}); described: {known}")


def named_variants(aircraft, folder=None):
    """The named variants of an aircraft (airframes/AIRCRAFT-variants/*.toml, the development set, or
    the specs in `folder`), in file order: (name, path, spec), the name the spec's `name` or else its
    file's."""
    out = []
    folder = folder or os.path.join(ROOT, "airframes", f"{aircraft}-variants")
    for p in sorted(glob.glob(os.path.join(folder, "*.toml"))):
        with open(p, "rb") as f:
            spec = tomllib.load(f)
        out.append((spec.get("name", os.path.basename(p)[:-5]), p, spec))
    return out


def aircraft_model(name):
    """The JSBSim model of the aircraft description aircraft/NAME.toml (its `[jsbsim] model`)."""
    return description(name)["jsbsim"]["model"]


def engine_file(data_root, model_dir, name):
    """The engine file JSBSim loads for `<engine file="NAME">` of the model in `model_dir`: the
    model's own `Engines/NAME.xml`, else the package's `engine/NAME.xml` under `data_root`."""
    local = os.path.join(model_dir, "Engines", name + ".xml")
    return local if os.path.exists(local) else os.path.join(data_root, "engine", name + ".xml")


@functools.cache
def jsbsim_root():
    """The pinned jsbsim package's data root, asked of the project's venv (or HIL_PYTHON)."""
    py = os.environ.get("HIL_PYTHON") or os.path.join(ROOT, ".venv", "bin", "python")
    try:
        r = subprocess.run([py, "-c", "import jsbsim; print(jsbsim.get_default_root_dir())"],
                           capture_output=True, text=True)
    except OSError as e:
        raise SystemExit(f"cannot run {py} ({e}): run scripts/bootstrap")
    if r.returncode != 0:
        raise SystemExit(f"no jsbsim package in {py}: run scripts/bootstrap\n{r.stderr[-500:]}")
    return r.stdout.strip()


def base_model(model):
    """What the pinned jsbsim package's MODEL/MODEL.xml offers a variant: its mean aerodynamic chord
    in inches (`<chord>`), the names of its aerodynamic terms, and whether every engine is a
    turbine (the only engine whose thrust scripts/airframe-variant scales)."""
    data = jsbsim_root()
    model_dir = os.path.join(data, "aircraft", model)
    xml = os.path.join(model_dir, model + ".xml")
    try:
        root = ET.parse(xml).getroot()
    except (OSError, ET.ParseError) as e:
        raise SystemExit(f"cannot read the JSBSim model {xml}: {e}")
    chord = root.find("metrics/chord")
    to_in = {"FT": 12.0, "IN": 1.0, "M": 39.37007874015748}
    try:
        mac_in = float(chord.text) * to_in[chord.get("unit", "FT")]
    except (AttributeError, TypeError, ValueError, KeyError):
        raise SystemExit(f"{xml}: no <chord> in FT, IN or M") from None
    terms = {fn.get("name", "").rsplit("/", 1)[-1] for fn in root.iterfind("aerodynamics/axis/function")}
    def turbine(file):
        return ET.parse(engine_file(data, model_dir, file)).getroot().tag == "turbine_engine"
    engines = [e.get("file") for e in root.iterfind("propulsion/engine")]
    return {"mac_in": mac_in, "terms": terms,
            "turbines": bool(engines) and all(turbine(e) for e in engines)}


def toml_key(k):
    """A bare key when TOML allows one, else a quoted one (`"aero/coefficient/CYb"`)."""
    return k if k.replace("_", "").replace("-", "").isalnum() else json.dumps(k)


def toml_value(v):
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{toml_key(k)} = {toml_value(x)}" for k, x in v.items()) + " }"
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, str):
        return json.dumps(v)
    return repr(v)


def toml_text(spec):
    """The spec as TOML: its scalars first, then one table per dict."""
    lines = [f"{toml_key(k)} = {toml_value(v)}" for k, v in spec.items() if not isinstance(v, dict)]
    for k, v in spec.items():
        if isinstance(v, dict):
            lines.append(f"[{toml_key(k)}]")
            lines += [f"{toml_key(kk)} = {toml_value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"
