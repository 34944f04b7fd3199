"""
The one-DOF oscillator against its closed form
==============================================

A mass on a spring, a massless node joined to it by a second spring, a stop under the
node: the period is known in closed form. MMS-HBM with H = 15 lies on it.
"""

import warnings
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

import mmshbm

# sphinx-gallery runs the examples in their folder without __file__
out = (Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()) / "out"
osc = mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0)
with warnings.catch_warnings():
    warnings.simplefilter("ignore", mmshbm.BranchWarning)
    branch = mmshbm.backbone(osc.model(), harmonics=15, max_amplitude=6.0)
A = np.linspace(0.5, 6.0, 200)
fig = Figure(figsize=(6.4, 4.2), layout="constrained")
ax = fig.add_subplot()
ax.plot([osc.frequency(a) for a in A], A, "k-", lw=3, alpha=0.3, label="closed form")
ax.plot(branch.frequency, branch.amplitude, "C0.-", ms=3, label="MMS-HBM, H = 15")
ax.set_xlabel("frequency (Hz)")
ax.set_ylabel("amplitude / gap")
ax.legend()
out.mkdir(parents=True, exist_ok=True)
fig.savefig(out / "oscillator.png", dpi=120)
pairs = zip(branch.frequency, branch.amplitude, strict=True)
err = max(abs(f - osc.frequency(a)) / osc.frequency(a) for f, a in pairs)
print(f"largest relative frequency error: {err:.2e}")
