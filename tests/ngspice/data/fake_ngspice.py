#!/usr/bin/env python3
"""A stand-in for ngspice that exits 0 and prints nothing alarming, but whose transient stops
halfway: it writes the wrdata file named in the deck with time points up to tstop / 2 only.
The harness must still reject it (last time point short of tstop)."""
import re
import sys

deck = open(sys.argv[-1]).read()
path = re.search(r"^wrdata\s+(\S+)", deck, re.M).group(1)
tstop = 20e-6  # the .tran of the deck the test uses (data/fails_mid_transient.cir)
with open(path, "w") as f:
    f.write(" time v(out)\n")
    for k in range(11):
        t = k * tstop / 20
        f.write(" %.12e %.12e\n" % (t, 0.0))
print("Circuit: fake\nngspice-39 done")
