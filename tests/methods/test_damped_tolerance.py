"""Damped nonlinear modes (EPMC) to a tolerance (``backbone(damped_model, tol=...)``,
mmshbm.methods.adaptive_damped): frequency and damping ratio against a much higher
fixed H at the same amplitudes, the finding where out of reach, bad input."""

import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm._warnings import BranchWarning
from mmshbm.results.tolerance_checks import tolerance_summary


@pytest.fixture(scope="module")
def osc():
    return mmshbm.OneDofOscillator(m=1.0, k1=1.0, k2=4.0, gap=1.0).model().with_damping(modal_ratio=0.02)


def _quiet(fn, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*args, **kwargs)


@pytest.mark.parametrize("tol", [1e-3, 1e-4])
def test_tol_is_met_against_a_much_higher_H(osc, tol):
    """Every family point's frequency and damping-ratio estimates meet tol; against the
    H = 64 mode solved at the same amplitudes (its own truncation below 1e-6 here: the
    H = 32 -> 64 differences) the true errors are at most 3 x tol."""
    b = _quiet(mmshbm.backbone, osc, tol=tol, max_amplitude=4.0)
    assert b.method == "epmc" and b.metadata["tolerance"]["tol"] == tol
    assert not [f for f in b.findings if f.kind == "tolerance_not_met"]
    front = b.family_front()
    assert np.all(b.frequency_error[front] <= tol) and np.all(b.records["damping_error"][front] <= tol)
    H = b.records["harmonics"]
    assert H.min() == 8 and H.max() > 8
    ref = _quiet(mmshbm.backbone, osc, harmonics=64, max_amplitude=4.0)
    p = ref.solve_at(b.amplitude[front])
    zeta = np.array([ref.solver.monitor(u)["damping_ratio"] for u in p.states])
    assert np.max(np.abs(b.frequency[front] / p.frequency - 1)) <= 3 * tol
    assert np.max(np.abs(b.damping_ratio[front] / zeta - 1)) <= 3 * tol
    assert tolerance_summary(b).startswith(f"tolerance {tol:g} met at every point")


def test_open_contact_points_keep_the_start_H(osc):
    """Below grazing the damped mode is the linear one at any H: estimates ~0, H stays 8."""
    b = _quiet(mmshbm.backbone, osc, tol=1e-6, max_amplitude=4.0)
    open_ = b.contact_force_max == 0
    assert open_.sum() >= 2
    assert np.all(b.frequency_error[open_] <= 1e-9) and np.all(b.records["damping_error"][open_] <= 1e-9)
    assert np.all(b.records["harmonics"][open_] == 8)


def test_out_of_reach_is_a_finding(osc):
    with pytest.warns(BranchWarning, match="frequency and damping ratio is not met"):
        b = mmshbm.backbone(osc, tol=1e-7, max_amplitude=4.0, max_harmonics=16)
    assert any(f.kind == "tolerance_not_met" for f in b.findings)


def test_bad_input(osc):
    with pytest.raises(ValueError, match="either harmonics"):
        mmshbm.backbone(osc, harmonics=5, tol=1e-3)
