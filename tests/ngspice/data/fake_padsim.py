#!/usr/bin/env python3
"""A stand-in for padsim in the harness's own tests: answers `NETLIST -o CSV --probe "a,b"` with
ngspice's waveform at the netlist's own settings, written as padsim's CSV. FAKE_PADSIM_SCALE
multiplies every value, FAKE_PADSIM_DELAY shifts the waveform later in time (seconds), so the
tests can check that the comparison accepts ngspice's own default answer and rejects a
perturbed one."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import spicecmp as sc  # noqa: E402

args = sys.argv[1:]
netlist = args[0]
csv_path = args[args.index("-o") + 1]
probes = args[args.index("--probe") + 1].split(",")
scale = float(os.environ.get("FAKE_PADSIM_SCALE", "1"))
delay = float(os.environ.get("FAKE_PADSIM_DELAY", "0"))
w = sc.run_ngspice(netlist, probes, os.path.dirname(os.path.abspath(csv_path)), tag="fake-padsim")
columns = []
for p in probes:
    y = w.signals[p.lower()]
    if delay:  # the value at t is the original's at t - delay (held before 0)
        y = sc.interpolate(w.time, y, [max(0.0, t - delay) for t in w.time])
    columns.append([v * scale for v in y])
with open(csv_path, "w") as f:
    f.write("time," + ",".join(probes) + "\n")
    for k, t in enumerate(w.time):
        f.write(",".join(repr(x) for x in [t] + [c[k] for c in columns]) + "\n")
