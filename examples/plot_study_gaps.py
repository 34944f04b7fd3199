"""
A study over the gap
====================

Backbones for two gaps and two values of H: each branch is drawn in units of its own
gap, the labels name every coordinate that varies, and the reference lines are drawn
once per distinct model.
"""

import warnings
from pathlib import Path

import mmshbm
from mmshbm.analysis.studies import run_study
from mmshbm.plotting import plot_study

# sphinx-gallery runs the examples in their folder without __file__
out = (Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()) / "out"
with warnings.catch_warnings():
    warnings.simplefilter("ignore", mmshbm.BranchWarning)
    study = run_study(harmonics=(3, 5), elements=(8,), params={"gap": [1e-3, 2e-3]}, max_amplitude=4,
                      unit="gap", executor="serial")
print(study.summary())
plot_study(study, path=out / "study_gaps.png", title="8 elements: gap 1 and 2 mm, H = 3 and 5")
