"""What scripts/airframe-sensitivity and scripts/airframe-randomise share: the F-16's mean
aerodynamic chord and a writer of the scripts/airframe-variant specs they make (top-level scalars,
then tables of scalars, lists and inline tables)."""

import json

MAC_IN = 11.32 * 12  # the F-16's mean aerodynamic chord (f16.xml <chord>), inches


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
