"""
A friction damper on the beam's tip: the optimal normal load
============================================================

The default beam with a damper pad pressed on its massless tip instead of the stop
(Coulomb friction, μ = 0.5, normal load N; 1 % modal damping; 1 N at mid-span, where
the amplitude is read). Below a critical load the tip slips and the first resonance
(45.8 Hz) is damped more and more; above it the pad holds the tip through most of the
period and the resonance moves toward the pinned-tip mode (197 Hz), damped less and less
as N grows. The resonance amplitude against N has its minimum in between: the optimal
normal load. Then the damped nonlinear mode (EPMC) at one load: frequency and damping
ratio against the amplitude of the node before the tip.
"""

import functools
import warnings
from pathlib import Path

import numpy as np

import mmshbm
from mmshbm.plotting.friction import plot_friction_mode, plot_normal_load

# sphinx-gallery runs the examples in their folder without __file__
out = (Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()) / "out"
make = functools.partial(mmshbm.tip_damper_model, at=0.5)  # called with normal_load=N
force = mmshbm.tip_damper_force(make(normal_load=0.0), 1.0)
loads = np.concatenate([[0.0], np.geomspace(0.05, 50, 13)])
study = mmshbm.normal_load_study(make, loads, force, band=(30, 250), harmonics=7)
print(study.to_text())
plot_normal_load(study, path=out / "friction_normal_load.png")

with warnings.catch_warnings():
    warnings.simplefilter("ignore", mmshbm.BranchWarning)
    mode = mmshbm.backbone(mmshbm.tip_damper_model(normal_load=1.0), harmonics=7, max_amplitude=1.5e-5)
plot_friction_mode(mode, path=out / "friction_mode.png", label="EPMC, μN = 0.5 N, H = 7")
first, last = (mode.frequency[0], mode.damping_ratio[0]), (mode.frequency[-1], mode.damping_ratio[-1])
print(f"EPMC: {len(mode.frequency)} points, from {first[0]:.1f} Hz (D = {first[1]:.4f}) to {last[0]:.1f} Hz "
      f"(D = {last[1]:.3f}) at {mode.amplitude[-1]:.2e} m; largest D {mode.damping_ratio.max():.2f}")
