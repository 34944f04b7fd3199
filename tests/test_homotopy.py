"""The Newton homotopy of the pinned system (:mod:`mmshbm.core.homotopy`) and the jumps
that land with it: checked against orbits reached by independent routes (Newton from a
nearby start, the twice-harmonic branch lowered to H)."""

import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm.core.homotopy import pinned_homotopy
from mmshbm.core.pinned import PinnedFailure, solve_at_amplitude
from mmshbm.methods.mms.family import _raised


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


def test_the_homotopy_reaches_the_orbit_newton_misses_from_the_same_start(chain_runs):
    """At 7 gaps, H = 5: Newton from the fundamental family's orbit raised to H does not
    converge; the homotopy from the same start reaches the orbit that Newton reaches from
    the H = 10 branch's orbit cut to H = 5 (an independent route) to round-off."""
    model, low, high = chain_runs
    P = low.solver
    target = 7.0 * model.gap
    aux, A, U = P._fundamental_branch(10 * model.gap)
    u1 = np.array([np.interp(target, A, U[:, i]) for i in range(U.shape[1])])
    u1 = solve_at_amplitude(aux, u1, target, max_iter=60)[0]
    start = _raised(aux, u1, P)
    with pytest.raises(PinnedFailure):
        solve_at_amplitude(P, start, target, max_iter=90)
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
