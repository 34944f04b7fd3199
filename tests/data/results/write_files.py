"""Write the result files of tests/results/test_result_files.py with whichever mmshbm is on
PYTHONPATH: ``PYTHONPATH=<tree> python write_files.py <tag> <folder>`` (tags used: ``v0.2``,
the tree of the 0.2.0 commit; ``main``, the tree before results shared one base class)."""

import sys
import warnings

import numpy as np

import mmshbm

warnings.simplefilter("ignore")
tag, out = sys.argv[1], sys.argv[2]
print(mmshbm.__file__, mmshbm.__version__)
osc = mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()
b = mmshbm.backbone(osc, harmonics=3, max_amplitude=2.0)
b.save(f"{out}/branch_osc_{tag}.npz")
M = np.diag([1.0, 1.0, 0.0])
K = np.array([[2000.0, -1000.0, 0.0], [-1000.0, 6000.0, -5000.0], [0.0, -5000.0, 5000.0]])
chain = mmshbm.Model.from_matrices(M, K, contact_dof=2, gap=0.01, stop_side=1)
b2 = mmshbm.backbone(chain, harmonics=3, max_amplitude=0.03)
b2.save(f"{out}/branch_chain_{tag}.npz")
d = osc.with_damping(modal_ratio=0.02)
f = np.zeros(d.n_dof)
f[0] = 0.3
r = mmshbm.frequency_response(d, f, (0.1, 0.3), harmonics=3)
r.save(f"{out}/response_osc_{tag}.npz")
print(len(b), len(b2), len(r), r.status)
