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
from mmshbm.plotting import plot_time_signals, points_at

# sphinx-gallery runs the examples in their folder without __file__
out = (Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()) / "out"
model = mmshbm.default_beam().model(21)
with warnings.catch_warnings():
    warnings.simplefilter("ignore", mmshbm.BranchWarning)
    branch = mmshbm.backbone(model, harmonics=5, max_amplitude=4e-3)
points = points_at(branch, [1.5e-3, 3e-3])
plot_time_signals(branch, points, path=out / "signals.png")
