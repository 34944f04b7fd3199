"""The amplitude DOF's row of the recovery (``_amplitude_row``, computed alone) against
the full recovery of every DOF with mass (``_recover``), on every condensation back end,
with and without pole unknowns.

Both sum the same products in the same grouping up to the order of a few dot products:
they differ by round-off, a few ε per term over ~n_l + n_modes terms (here ~60: ~1e-14 of the
row's largest entry); 1e-12 bounds that with room and fails on any wrong term (each is
O(1) of the row for random motion).
"""

from __future__ import annotations

import numpy as np
import pytest

from mmshbm.methods.mms.conservative import MMSHBMProblem


@pytest.fixture(scope="module")
def clearance_beam():
    from validation import corpus

    return corpus.generate(291, 29)[290].model()  # a beam clearance, amplitude DOF with mass


@pytest.mark.parametrize("poles", [True, False])
@pytest.mark.parametrize("backend", ["modal", "banded", "splu"])
def test_the_amplitude_row_is_that_of_the_full_recovery(clearance_beam, backend, poles):
    model = clearance_beam
    p = MMSHBMProblem(model, harmonics=15, backend=backend, poles=poles)
    assert not p._amp_in_c and (p.n_poles > 15 if poles else p.n_poles == 0)
    i = int(np.searchsorted(model.l, model.amplitude_dof))
    rng = np.random.default_rng(7)
    w1 = 2 * np.pi * model.linear_frequencies(1)[0]
    for omega in (1.05 * w1, 1.05 * w1, 1.2 * w1):  # the second: the modal factors of the last Ω, reused
        a = rng.standard_normal((p.H + 1, p.n_c))
        eta = rng.standard_normal(p.n_poles)
        row = p._amplitude_row(a, omega, eta)
        full = p._recover(a, omega, eta)[i]
        ref = np.concatenate([[full[0]], full[1::2]])
        assert row.shape == (p.H + 1,)
        assert np.abs(row - ref).max() <= 1e-12 * np.abs(ref).max()
