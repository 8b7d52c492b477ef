"""Steps JSBSim for hil-sim. Nothing else lives here: maneuvers, sensors and datasets are Rust.

Protocol (one request per stdin line, fields separated by TAB; one framed reply per request on the
ORIGINAL stdout):
  reply frame = status byte (b'O' ok / b'E' error) + u32 little-endian payload length + payload.
  On start the bridge sends one frame: b'O' + JSBSim version string, or b'E' + why it cannot run.
  load\tSCRIPT\tINITFILE   load a runscript at the dt it declares, exactly as stock JSBSim runs it
                          (INITFILE may be empty: JSBSim looks in the aircraft folder), run the
                          initial conditions; payload = f64 little-endian dt in seconds
  watch\tP1\tP2...        the properties returned after every step, in this order; a name
                          prefixed with '?' is optional: absent from the model, it reads NaN
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


def nan():
    return float("nan")


def main():
    try:
        import jsbsim
    except Exception as e:  # the Rust side turns this into "run scripts/bootstrap"
        reply(False, f"cannot import jsbsim with {sys.executable}: {e}".encode())
        return
    fdm = jsbsim.FGFDMExec(jsbsim.get_default_root_dir())
    fdm.set_debug_level(0)
    pm = fdm.get_property_manager()
    getters = []
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
                reply(True, struct.pack("<d", fdm.get_delta_t()))
            elif cmd == "watch":
                found, missing = [], []
                for p in f[1:]:
                    optional = p.startswith("?")
                    n = pm.get_node(p[1:] if optional else p, False)
                    if n is not None or optional:
                        found.append(n)
                    else:
                        missing.append(p)
                if missing:
                    reply(False, ("unknown properties: " + ", ".join(missing)).encode())
                else:
                    getters = [nan if n is None else n.get_double_value for n in found]
                    reply(True)
            elif cmd == "step":
                n = int(f[1])
                rows = []
                done = 0
                pack = struct.Struct("<%dd" % len(getters)).pack
                for _ in range(n):
                    alive = fdm.run()
                    rows.append(pack(*[get() for get in getters]))
                    done += 1
                    if not alive:
                        break
                reply(True, struct.pack("<I", done) + b"".join(rows))
            elif cmd == "run":
                n = int(f[1])
                run = fdm.run
                done = 0
                while done < n:
                    done += 1
                    if not run():
                        break
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
