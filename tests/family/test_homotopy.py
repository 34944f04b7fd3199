"""The Newton homotopy of the pinned system (:mod:`mmshbm.core.homotopy`) and the jumps
that land with it: checked against orbits reached by independent routes (Newton from a
nearby start, the twice-harmonic branch lowered to H)."""

import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm.core.homotopy import pinned_homotopy
from mmshbm.core.pinned import PinnedFailure, solve_at_amplitude
from mmshbm.methods.mms.landings import _raised


def _rattling_chain():
    """A heavy mass (23.24 kg on 1306.9 N/m to the ground) carrying a light chain (0.050 kg
    through 80.5 N/m, 0.471 kg through 378.6 N/m), a massless contact node on the last mass
    through 531.6 N/m, a stop at −1.327 mm (corpus seed 18, index 74). Open modes 1.1715,
    1.8594, 15.80 Hz; the heavy mass alone with the last mass held: 1.2236 Hz."""
    M = np.diag([23.236879448406484, 0.05002382458983747, 0.4705629419112473, 0.0])
    k0, k1, k2, kc = 1306.8784471915728, 80.5464472993125, 378.58351907016043, 531.5778951323078
    K = np.array([[k0 + k1, -k1, 0.0, 0.0], [-k1, k1 + k2, -k2, 0.0],
                  [0.0, -k2, k2 + kc, -kc], [0.0, 0.0, -kc, kc]])
    return mmshbm.Model.from_matrices(M, K, 3, 0.0013273980976594023, -1)


@pytest.fixture(scope="module")
def chain_runs():
    model = _rattling_chain()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mmshbm.BranchWarning)
        low = mmshbm.backbone(model, harmonics=5, max_amplitude=10 * model.gap)
        high = mmshbm.backbone(model, harmonics=10, max_amplitude=10 * model.gap)
    return model, low, high


def _lowered(high, low_problem, amplitude):
    """The H-harmonic start from the twice-harmonic branch's orbit nearest ``amplitude``:
    its first H + 1 harmonics."""
    j = int(np.argmin(abs(np.asarray(high.amplitude) - amplitude)))
    a, omega = high.solver.unpack(high.states[j])
    return low_problem.pack(a[: low_problem.H + 1].copy(), omega)


def test_the_homotopy_reaches_the_orbit_from_the_raised_start(chain_runs):
    """At 7 gaps, H = 5, from the fundamental family's orbit raised to H: the homotopy
    reaches the orbit that Newton reaches from the H = 10 branch's orbit cut to H = 5 (an
    independent route) to round-off. Where plain Newton from that start goes after 90
    iterations is not asserted: from a start this far from the orbit its path depends on
    round-off (it has been seen to reach the orbit on one machine and a phase-shifted
    orbit of another family on another)."""
    model, low, high = chain_runs
    P = low.solver
    target = 7.0 * model.gap
    aux, A, U = P._fundamental_branch(10 * model.gap)
    u1 = np.array([np.interp(target, A, U[:, i]) for i in range(U.shape[1])])
    u1 = solve_at_amplitude(aux, u1, target, max_iter=60)[0]
    start = _raised(aux, u1, P)
    u = pinned_homotopy(P, start, target)[0]
    ref = solve_at_amplitude(P, _lowered(high, P, target), target, max_iter=60)[0]
    assert abs(P.frequency_of(u) / P.frequency_of(ref) - 1) < 1e-9
    assert np.abs(u - ref).max() < 1e-7 * np.abs(ref).max()
    assert P.fundamental_share(u) > 0.9


def test_the_default_backbone_lands_beyond_the_fold_on_the_lowered_family(chain_runs):
    """H = 5 folds at 6.7 gaps at 1.2225 Hz (before: "jump failed: the branch turns back in
    amplitude at the frontier"). The family resumes below that frequency, at 1.19 Hz,
    as at H = 10 (which jumps from 3.5 to 3.9 gaps onto it); the run lands there and
    reaches 10 gaps, on the orbits that the H = 10 branch cut to H = 5 converges to."""
    model, low, high = chain_runs
    assert low.completed and high.completed
    jumps = [sp for sp in low.special_points if sp.kind == "jump"]
    assert len(jumps) == 1 and jumps[0].data["frequency_to"] < jumps[0].data["frequency_from"] - 0.02
    P = low.solver
    for gaps in (7.0, 8.5, 10.0):
        target = gaps * model.gap
        ref = solve_at_amplitude(P, _lowered(high, P, target), target, max_iter=60)[0]
        assert abs(low.frequency_at(target) / P.frequency_of(ref) - 1) < 1e-9


def test_a_homotopy_that_cannot_end_says_so():
    """A step budget too small to reach s = 1 ends with PinnedFailure naming it."""
    model = _rattling_chain()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mmshbm.BranchWarning)
        b = mmshbm.backbone(model, harmonics=5, max_amplitude=2 * model.gap)
    P = b.solver
    aux, A, U = P._fundamental_branch(10 * model.gap)
    target = 7.0 * model.gap
    u1 = np.array([np.interp(target, A, U[:, i]) for i in range(U.shape[1])])
    with pytest.raises(PinnedFailure, match="did not reach its end in 2 steps"):
        pinned_homotopy(P, _raised(aux, u1, P), target, max_steps=2)
    with pytest.raises(ValueError, match="amplitude must be positive"):
        pinned_homotopy(P, _raised(aux, u1, P), 0.0)


class _Cubic:
    """R(u) = [x³ + x − w, y − 2x], amplitude A(u) = w + 1: pinned at A* = 11 the only
    solution is (x, y, w) = (2, 4, 10). ``sparse``: J as a scipy.sparse matrix."""

    n_unknowns = 3

    def __init__(self, sparse: bool):
        self.sparse = sparse

    def residual(self, u):
        x, y, w = u
        return np.array([x**3 + x - w, y - 2 * x])

    def residual_and_jacobian(self, u):
        import scipy.sparse as sp

        x = u[0]
        J = np.array([[3 * x**2 + 1, 0.0, -1.0], [-2.0, 1.0, 0.0]])
        return self.residual(u), (sp.csr_matrix(J) if self.sparse else J)

    def amplitude_and_gradient(self, u):
        return float(u[2] + 1.0), np.array([0.0, 0.0, 1.0])

    def amplitude_value(self, u):
        return float(u[2] + 1.0)

    def monitor(self, u):
        return {"amplitude": float(u[2] + 1.0)}


@pytest.mark.parametrize("sparse", [False, True])
def test_the_homotopy_solves_a_problem_of_any_jacobian_to_its_closed_form(sparse):
    """A user problem (dense or sparse Jacobian) from a start far from its solution: the
    homotopy's end is the closed-form solution (2, 4, 10): with the final Newton solve's
    residual below 1e-13, x is within 1e-13 / (3x² + 1) = 7.7e-15 of 2, y twice that of
    4, and w within 11e-13 of 10 (the amplitude row is relative to A* = 11)."""
    u = pinned_homotopy(_Cubic(sparse), np.array([-3.0, 5.0, 0.0]), 11.0, tol=1e-13)[0]
    assert abs(u[0] - 2.0) <= 1e-13 / 13 + 1e-15
    assert abs(u[1] - 4.0) <= 2e-13 / 13 + 1e-15
    assert abs(u[2] - 10.0) <= 11e-13 + 1e-14
