"""Steps JSBSim for hil-sim. Nothing else lives here: maneuvers, sensors and datasets are Rust.

Protocol (one request per stdin line, fields separated by TAB; one framed reply per request on the
ORIGINAL stdout):
  reply frame = status byte (b'O' ok / b'E' error) + u32 little-endian payload length + payload.
  On start the bridge sends one frame: b'O' + JSBSim version string, or b'E' + why it cannot run.
  load\tSCRIPT\tINITFILE   load a runscript at the dt it declares, exactly as stock JSBSim runs it
                          (INITFILE may be empty: JSBSim looks in the aircraft folder), run the
                          initial conditions; payload = f64 little-endian dt in seconds
  watch\tK\tP1\tP2...     the properties returned after every step, in this order; a name
                          prefixed with '?' is optional: absent from the model, it reads NaN; a
                          name prefixed with '~' is read only on every K-th step since `load`
                          (the 20 Hz sample instants) and reads NaN on the others (the two
                          prefixes combine as '~?'); K 0 reads every property every step
  step\tN                 run up to N steps; payload = u32 steps done (fewer when the script ended)
                          + that many rows of little-endian f64, one per watched property
  run\tN                  run up to N steps reading nothing (raw JSBSim stepping, the benchmark's
                          baseline); payload = u32 steps done
  quit
"""

import os
import struct
import sys
import xml.etree.ElementTree as ET

# JSBSim prints its banner and <notify/> messages on fd 1: keep the real stdout for frames only and
# send everything else to stderr, at the file-descriptor level so C++ output follows too.
_frames = os.fdopen(os.dup(1), "wb", buffering=0)
os.dup2(2, 1)
sys.stdout = sys.stderr


def reply(ok, payload=b""):
    _frames.write((b"O" if ok else b"E") + struct.pack("<I", len(payload)) + payload)


def sampler(getters):
    """One function that reads the watched properties and packs the row: `pack(g0(), g1(), ...)`
    with the getters as local names, NaN where a getter is None. Against a loop over the getters
    building a list, this saves the list, the iteration and a global lookup per property, per
    120 Hz step (docs/results/generate-bench.md)."""
    names = [f"g{i}" for i in range(len(getters))]
    scope = {n: g for n, g in zip(names, getters) if g is not None}
    scope["pack"] = struct.Struct("<%dd" % len(getters)).pack
    scope["nan_"] = float("nan")
    args = ", ".join(f"{n}={n}" for n in list(scope))
    body = ", ".join("nan_" if g is None else f"{n}()" for n, g in zip(names, getters))
    exec(f"def sample({args}):\n    return pack({body})\n", scope)
    return scope["sample"]


def main():
    try:
        import jsbsim
    except Exception as e:  # the Rust side turns this into "run scripts/bootstrap"
        reply(False, f"cannot import jsbsim with {sys.executable}: {e}".encode())
        return
    fdm = jsbsim.FGFDMExec(jsbsim.get_default_root_dir())
    fdm.set_debug_level(0)
    pm = fdm.get_property_manager()
    sample = fast = sampler([])
    every, steps = 1, 0
    reply(True, jsbsim.__version__.encode())
    for line in sys.stdin:
        f = line.rstrip("\n").split("\t")
        cmd = f[0]
        try:
            if cmd == "load":
                script, init = f[1], f[2]
                try:
                    ET.parse(script)
                except ET.ParseError as e:
                    reply(False, f"invalid XML: {e}".encode())
                    continue
                # dt 0.0: the script's own dt. Passing a rate here overrides the script's, and
                # JSBSim adds dt to its clock before checking events, so a different dt moves
                # every time-triggered event and the flight no longer matches stock JSBSim.
                if not fdm.load_script(script, 0.0, init):
                    reply(False, b"JSBSim refused the script (see its messages above)")
                    continue
                if not fdm.run_ic():
                    reply(False, b"JSBSim could not apply the initial conditions")
                    continue
                steps = 0
                reply(True, struct.pack("<d", fdm.get_delta_t()))
            elif cmd == "watch":
                every = int(f[1]) or 1  # 0: every property every step
                found, missing, sampled = [], [], []
                for p in f[2:]:
                    sampled.append(p.startswith("~"))
                    p = p.lstrip("~")
                    optional = p.startswith("?")
                    n = pm.get_node(p[1:] if optional else p, False)
                    if n is not None or optional:
                        found.append(n)
                    else:
                        missing.append(p)
                if missing:
                    reply(False, ("unknown properties: " + ", ".join(missing)).encode())
                else:
                    getters = [None if n is None else n.get_double_value for n in found]
                    sample = sampler(getters)
                    fast = sampler([None if s else g for g, s in zip(getters, sampled)])
                    reply(True)
            elif cmd == "step":
                n = int(f[1])
                rows = []
                append = rows.append
                run = fdm.run
                base = steps
                done = 0
                while done < n:
                    done += 1
                    alive = run()
                    append(sample() if (base + done) % every == 0 else fast())
                    if not alive:
                        break
                steps = base + done
                reply(True, struct.pack("<I", done) + b"".join(rows))
            elif cmd == "run":
                n = int(f[1])
                run = fdm.run
                done = 0
                while done < n:
                    done += 1
                    if not run():
                        break
                steps += done
                reply(True, struct.pack("<I", done))
            elif cmd == "quit":
                reply(True)
                return
            else:
                reply(False, f"unknown command {cmd!r}".encode())
        except Exception as e:
            reply(False, f"{cmd}: {type(e).__name__}: {e}".encode())


if __name__ == "__main__":
    main()
