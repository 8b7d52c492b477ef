"""What scripts/airframe-sensitivity and scripts/airframe-randomise share: the F-16's mean
aerodynamic chord, the aerodynamic terms the randomiser draws and how widely, and a writer of the
scripts/airframe-variant specs they make (top-level scalars, then tables of scalars, lists and
inline tables)."""

import json

MAC_IN = 11.32 * 12  # the F-16's mean aerodynamic chord (f16.xml <chord>), inches

# `scripts/airframe-randomise --terms`: each term times a factor uniform in 1 ± width·spread, drawn in
# this order (a seed's draws depend on it); SPREAD is its default spread.
SPREAD = 0.1
TERM_WIDTHS = (("CLDflaps", 2.0), ("CLDlef", 2.0), ("CYDa", 2.0), ("CYdr", 2.0), ("CYb", 1.0))


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
