"""Steps JSBSim for hil-sim. Nothing else lives here: maneuvers, sensors and datasets are Rust.

Protocol (one request per stdin line, fields separated by TAB; one framed reply per request on the
ORIGINAL stdout):
  reply frame = status byte (b'O' ok / b'E' error) + u32 little-endian payload length + payload.
  Started as `python -c SOURCE AIRCRAFT_DIR MODEL`: with a directory (not ""), JSBSim loads
  aircraft from there (`set_aircraft_path`, as stock JSBSim does), else from the package's own
  aircraft folder; MODEL is the aircraft's JSBSim name (its description's, e.g. f16).
  On start the bridge sends one frame: b'O' + JSBSim version string + '\n' + the absolute path of
  the MODEL/MODEL.xml it will load, or b'E' + why it cannot run.
  load\tSCRIPT\tINITFILE   load a runscript at the dt it declares, exactly as stock JSBSim runs it
                          (INITFILE may be empty: JSBSim looks in the aircraft folder), run the
                          initial conditions; payload = f64 little-endian dt in seconds
  watch\tL\tM0..ML-1\tP1\tP2...
                          the properties returned after every step, in this order, and when each
                          is read: step k (counted from 0 since `load`) reads property i when
                          k == 0 or bit i of the hexadecimal mask M(k mod L) is set, and NaN
                          otherwise (a property needed at some steps only costs nothing at the
                          others); a name prefixed with '?' is optional: absent from the model, it
                          reads NaN
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
    for part in ((b"O" if ok else b"E") + struct.pack("<I", len(payload)), payload):
        view = memoryview(part)
        while view:  # an unbuffered write may take only part of it
            view = view[_frames.write(view):]


def sampler(getters):
    """One function that reads the watched properties and packs the row into a buffer:
    `pack_into(buf, off, g0(), g1(), ...)` with the getters as local names, NaN where a getter is
    None. Against a loop over the getters building a list, this saves the list, the iteration and
    a global lookup per property, per 120 Hz step; writing into one reused buffer saves a bytes
    object per step and their join per reply (docs/results/generate-bench.md)."""
    names = [f"g{i}" for i in range(len(getters))]
    scope = {n: g for n, g in zip(names, getters) if g is not None}
    scope["pack_into"] = struct.Struct("<%dd" % len(getters)).pack_into
    scope["nan_"] = float("nan")
    args = ", ".join(f"{n}={n}" for n in list(scope))
    body = "".join(", nan_" if g is None else f", {n}()" for n, g in zip(names, getters))
    exec(f"def sample(buf, off, {args}):\n    pack_into(buf, off{body})\n", scope)
    return scope["sample"]


def main():
    try:
        import jsbsim
    except Exception as e:  # the Rust side turns this into "run scripts/bootstrap"
        reply(False, f"cannot import jsbsim with {sys.executable}: {e}".encode())
        return
    root = jsbsim.get_default_root_dir()
    fdm = jsbsim.FGFDMExec(root)
    fdm.set_debug_level(0)
    aircraft_dir = sys.argv[1] if len(sys.argv) > 1 and sys.argv[1] else os.path.join(root, "aircraft")
    if len(sys.argv) > 1 and sys.argv[1]:
        fdm.set_aircraft_path(os.path.abspath(sys.argv[1]))
    pm = fdm.get_property_manager()
    full = sampler([])
    cycle, steps, width, buf = [full], 0, 0, bytearray(4)
    model = sys.argv[2] if len(sys.argv) > 2 else ""
    xml = os.path.abspath(os.path.join(aircraft_dir, model, model + ".xml"))
    reply(True, (jsbsim.__version__ + "\n" + xml).encode())
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
                period = int(f[1])
                masks = [int(m, 16) for m in f[2:2 + period]]
                if period < 1 or len(masks) != period:
                    reply(False, f"watch: {period} masks announced, {len(masks)} sent".encode())
                    continue
                found, missing = [], []
                for p in f[2 + period:]:
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
                    width = len(getters)
                    full = sampler(getters)
                    made = {}
                    for m in masks:
                        if m not in made:
                            made[m] = sampler([g if m >> i & 1 else None for i, g in enumerate(getters)])
                    cycle = [made[m] for m in masks]
                    reply(True)
            elif cmd == "step":
                n = int(f[1])
                row = 8 * width
                if len(buf) < 4 + n * row:
                    buf = bytearray(4 + n * row)
                run = fdm.run
                length = len(cycle)
                done, off = 0, 4
                while done < n:
                    k = steps + done
                    done += 1
                    alive = run()
                    (cycle[k % length] if k else full)(buf, off)
                    off += row
                    if not alive:
                        break
                steps += done
                struct.pack_into("<I", buf, 0, done)
                reply(True, memoryview(buf)[:off])
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
