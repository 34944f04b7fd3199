"""
Admissible signals beside the truncated series
==============================================

With few harmonics the Fourier series of the massless tip passes through the stop.
Driving the exact static contact problem with the Fourier motion of the DOFs with mass
gives tip signals that never do (solid); the truncated series is dashed.
"""

import warnings
from pathlib import Path

import mmshbm
from mmshbm.plotting import plot_time_signals

# sphinx-gallery runs the examples in their folder without __file__
out = (Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()) / "out"
model = mmshbm.default_beam().model(21)
with warnings.catch_warnings():
    warnings.simplefilter("ignore", mmshbm.BranchWarning)
    branch = mmshbm.backbone(model, harmonics=5, max_amplitude=4e-3)
points = branch.solve_at([1.5, 3.0], unit="gap")  # on the backbone, past the 5:2 tongue at 2 gaps
plot_time_signals(points, [0, 1], path=out / "signals.png")
