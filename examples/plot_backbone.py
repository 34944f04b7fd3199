"""
The backbone of the default beam
================================

The first nonlinear mode of the clamped Timoshenko beam with a stop under its tip
(21 elements, H = 5), with the linear frequency, the zero-gap limit, the internal
resonances f_k/n and the special points; the branch checks say what the branch is.
"""

import warnings
from pathlib import Path

import mmshbm
from mmshbm.plotting import plot_backbone

# sphinx-gallery runs the examples in their folder without __file__
out = (Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()) / "out"
model = mmshbm.default_beam().model(21)
with warnings.catch_warnings():
    warnings.simplefilter("ignore", mmshbm.BranchWarning)  # printed below instead
    branch = mmshbm.backbone(model, harmonics=5)
print(branch)
for finding in branch.findings:
    print(f"{finding.kind}: {finding.message}")
plot_backbone(branch, path=out / "backbone.png", title="default beam, 21 elements, H = 5")
