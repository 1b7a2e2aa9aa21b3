"""The Python side of the probe overhead measurement: what `gcr solve cornell-box --probes IN
--probe-out OUT` does, through NumPy arrays.

    python probes.py probes20k.txt b.txt
"""

import sys

import numpy as np

import gcr

rows = np.loadtxt(sys.argv[1])
solution = gcr.solve(gcr.Scene.load("cornell-box"))
values, std_errors = solution.radiosity(rows[:, :3], rows[:, 3:])
np.savetxt(sys.argv[2], values, fmt="%.17g")
