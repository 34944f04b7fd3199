"""The deflated search beyond a frontier (:mod:`mmshbm.family.deflation`) on a problem
whose orbits are known in closed form: at amplitude A the circle x² + y² = 1 meets the
line x = A − 2 in exactly two points, y = ±√(1 − (A − 2)²)."""

import math

import numpy as np
import pytest

from mmshbm.core.pinned import PinnedFailure
from mmshbm.family.deflation import KnownOrbit, deflated_solve, deflation, search_beyond
from mmshbm.family.end import FamilyEnded
from mmshbm.family.guard import FamilyGuard
from mmshbm.family.options import FamilyOptions


class Circle:
    """u = (x, y); R(u) = x² + y² − 1; amplitude x + 2; frequency 1 + y Hz; fundamental
    share ``share0 + share1·y``."""

    n_unknowns = 2

    def __init__(self, share0: float, share1: float):
        self.share0, self.share1 = share0, share1

    def residual(self, u):
        return np.array([u[0] ** 2 + u[1] ** 2 - 1.0])

    def residual_and_jacobian(self, u):
        return self.residual(u), np.array([[2 * u[0], 2 * u[1]]])

    def monitor(self, u):
        return {"amplitude": float(u[0] + 2.0), "frequency": float(1.0 + u[1]),
                "fundamental_share": float(self.share0 + self.share1 * u[1])}


def _roots(A):
    x = A - 2.0
    y = math.sqrt(1.0 - x * x)
    return np.array([x, y]), np.array([x, -y])


def test_deflation_finds_both_orbits_from_one_start_and_then_none():
    """From one start Newton finds one orbit; with it deflated, the other; with both
    deflated it fails: it never returns a known orbit (to 1e-12, Newton's tolerance times
    the condition, both orbits being well separated)."""
    A = 1.53
    up, down = _roots(A)
    problem = Circle(0.6, 0.1)
    start = np.array([A - 2.0, 0.3])
    u1 = deflated_solve(problem, start, A, [])[0]
    u2 = deflated_solve(problem, start, A, [u1])[0]
    assert min(np.abs(u1 - up).max(), np.abs(u1 - down).max()) < 1e-12
    other = down if np.abs(u1 - up).max() < 1e-12 else up
    assert np.abs(u2 - other).max() < 1e-12
    rng = np.random.default_rng(5)
    for u0 in rng.uniform(-1.5, 1.5, size=(20, 2)):
        with pytest.raises(PinnedFailure):
            deflated_solve(problem, u0, A, [u1, u2])


def test_deflation_operator_is_infinite_at_a_known_orbit_and_tends_to_the_shift_far_away():
    """M(u) = Π (‖u − u_k‖⁻² + σ): the known orbit is a pole, far from it M → σ, and the
    gradient of log M is that of −log ‖u − u_k‖² near it (finite differences, 1e-6)."""
    uk = np.array([0.2, -0.4])
    assert deflation(uk, [uk], 1.0)[0] == math.inf
    assert abs(deflation(uk + 1e6, [uk], 1.0)[0] - 1.0) < 1e-11
    u = np.array([0.5, 0.1])
    _, w = deflation(u, [uk], 1.0)
    h = 1e-6
    log_m = [math.log(deflation(u + s * h * e, [uk], 1.0)[0]) for e in np.eye(2) for s in (1, -1)]
    fd = [(log_m[2 * i] - log_m[2 * i + 1]) / (2 * h) for i in range(2)]
    assert np.abs(w - fd).max() < 1e-6


class _Start:
    def __init__(self, y):
        self.y = y

    def landings(self, us, recs, guard, amplitude_max):
        return []

    def starts(self, us, recs, guard, amplitude, amplitude_max):
        return [("fixed", np.array([amplitude - 2.0, self.y]))]


def _branch(problem, amplitudes):
    us = [_roots(a)[0] for a in amplitudes]
    recs = [problem.monitor(u) for u in us]
    guard = FamilyGuard(0.5, 60)
    for i, rec in enumerate(recs):
        guard.observe(i, rec)
    return us, recs, guard


def test_the_search_returns_both_coexisting_orbits_and_lands_on_the_larger_share():
    """Both orbits at the first target hold the family's share (0.6 ± 0.1·y): a start
    stops at its first orbit of the family, so from a start below (y = −0.5) and one
    above (y = 0.5) the search finds both (two "landed" attempts) and lands on the one
    of larger share, y > 0, whichever start found it."""
    problem = Circle(0.6, 0.1)
    us, recs, guard = _branch(problem, [1.3, 1.4, 1.5])
    options = FamilyOptions()
    u, _, _, rec, t, target, origin = search_beyond(
        problem, guard, us, recs, options=options, amplitude_max=2.5, newton_tol=1e-12, max_newton=10,
        monitor=lambda p, v: p.monitor(v), starts=_Starts(-0.5, 0.5))
    assert target == pytest.approx(1.5 * 1.02, rel=1e-15) and origin == 2
    assert np.abs(u - _roots(target)[0]).max() < 1e-12
    assert abs(rec["fundamental_share"] - (0.6 + 0.1 * u[1])) < 1e-15


def test_a_search_that_finds_only_orbits_off_the_family_ends_it_with_what_it_tried():
    """Shares 0.45 ± 0.04·y: every orbit fails the predicate. The search tries each target
    (deflating what it found), ends with a FamilyEnd whose attempts list both orbits per
    target as off the family, and the last target is the bound."""
    problem = Circle(0.45, 0.04)
    us, recs, guard = _branch(problem, [1.3, 1.4, 1.5])
    for rec in recs:
        rec["fundamental_share"] = 0.9  # the branch below was on the family
    guard = FamilyGuard(0.5, 60)
    for i, rec in enumerate(recs):
        guard.observe(i, rec)
    options = FamilyOptions()
    with pytest.raises(FamilyEnded) as info:
        search_beyond(problem, guard, us, recs, options=options, amplitude_max=1.6, newton_tol=1e-12,
                      max_newton=10, monitor=lambda p, v: p.monitor(v), starts=_Start(0.2))
    end = info.value.end
    assert not end.ended and end.searched_to == 1.6 and end.frontier == 1.5
    assert end.outcomes()["off the family"] == 2 * len({a.amplitude for a in end.attempts})
    assert "landed" not in end.outcomes()
    with pytest.raises(KnownOrbit):
        deflated_solve(problem, us[-1], 1.5, [us[-1]], max_iter=0)


@pytest.mark.parametrize("frontier, bound", [(1.0, 10.0), (0.3, 10.0), (1.0, 1.05), (1.0, 1e3)])
def test_the_targets_double_their_step_then_grow_by_at_most_the_target_ratio_to_the_bound(frontier, bound):
    """frontier·(1 + jump_step·2^i) while consecutive targets are less than target_ratio
    apart, then that ratio, up to the bound or frontier/jump_step, whichever is lower."""
    from mmshbm.family.deflation import _targets

    options = FamilyOptions()
    t = np.array(_targets(frontier, bound, options))
    assert t[0] == pytest.approx(frontier * (1 + options.jump_step))
    assert t[-1] == pytest.approx(min(bound, frontier / options.jump_step))
    ratios = t[1:] / t[:-1]
    assert np.all(ratios > 1.0) and np.all(ratios <= options.target_ratio * (1 + 1e-12))
    doubling = frontier * (1 + options.jump_step * 2.0 ** np.arange(4))
    n = min(len(t), 4)
    assert np.allclose(t[:n], np.minimum(doubling[:n], min(bound, frontier / options.jump_step)))


class Quartic:
    """u = (x, y); R(u) = Π_k (y − r_k) with roots ``ROOTS``; amplitude x + 2; frequency
    1 + y Hz; fundamental share 0.45 + 0.5·y: only the root y = 0.5 (share 0.7) holds the
    family's majority, the three at y <= −0.1 (share <= 0.4) do not."""

    ROOTS = (-0.3, -0.2, -0.1, 0.5)
    n_unknowns = 2

    def residual(self, u):
        return np.array([np.prod([u[1] - r for r in self.ROOTS])])

    def residual_and_jacobian(self, u):
        d = sum(np.prod([u[1] - r for r in self.ROOTS if r != q]) for q in self.ROOTS)
        return self.residual(u), np.array([[0.0, d]])

    def monitor(self, u):
        return {"amplitude": float(u[0] + 2.0), "frequency": float(1.0 + u[1]),
                "fundamental_share": float(0.45 + 0.5 * u[1])}


class _Starts:
    def __init__(self, *ys):
        self.ys = ys

    def landings(self, us, recs, guard, amplitude_max):
        return []

    def starts(self, us, recs, guard, amplitude, amplitude_max):
        return [(f"y = {y}", np.array([amplitude - 2.0, y])) for y in self.ys]


def test_orbits_off_the_family_found_from_the_first_start_leave_the_later_starts_their_turn():
    """The first start (y = −0.22) lies among the three orbits off the family: its three
    deflated solves find exactly those (checked below, to 1e-12). The second start
    (y = 0.45) lies by the family's orbit y = 0.5. Each start's deflation depth is
    ``max_roots`` = 3, so the second start is still tried at the first target and the
    search lands there on y = 0.5 (to 1e-12, Newton's tolerance on a simple root); a
    budget of three orbits per target would end at the first start, at every target."""
    problem = Quartic()
    options = FamilyOptions(max_roots=3)
    A = 1.5 * (1 + options.jump_step)
    known = []
    for _ in range(3):
        known.append(deflated_solve(problem, np.array([A - 2.0, -0.22]), A, known, tol=1e-12,
                                    max_iter=30)[0])
    assert sorted(round(float(u[1]), 9) for u in known) == [-0.3, -0.2, -0.1]
    amplitudes = [1.3, 1.4, 1.5]
    us = [np.array([a - 2.0, 0.5]) for a in amplitudes]
    recs = [problem.monitor(u) for u in us]
    guard = FamilyGuard(0.5, 60)
    for i, rec in enumerate(recs):
        guard.observe(i, rec)
    u, _, _, rec, t, target, origin = search_beyond(
        problem, guard, us, recs, options=options, amplitude_max=2.5, newton_tol=1e-12, max_newton=10,
        monitor=lambda p, v: p.monitor(v), starts=_Starts(-0.22, 0.45))
    assert target == pytest.approx(A, rel=1e-15) and origin == 2
    assert np.abs(u - np.array([A - 2.0, 0.5])).max() < 1e-12
    assert rec["fundamental_share"] >= options.family_share


class _Costly(_Starts):
    """Regular starts at ``ys``; the costly start y = 0.45 (by the family's orbit) only as
    ``last_resort``, counting its calls."""

    def __init__(self, *ys):
        super().__init__(*ys)
        self.calls = []

    def last_resort(self, us, recs, guard, amplitude, amplitude_max):
        self.calls.append(amplitude)
        return [("costly", np.array([amplitude - 2.0, 0.45]))]


def _quartic_branch(problem):
    us = [np.array([a - 2.0, 0.5]) for a in (1.3, 1.4, 1.5)]
    recs = [problem.monitor(u) for u in us]
    guard = FamilyGuard(0.5, 60)
    for i, rec in enumerate(recs):
        guard.observe(i, rec)
    return us, recs, guard


def test_the_costly_starts_run_at_the_targets_in_turn_only_where_the_others_found_nothing():
    """With only starts among the orbits off the family, every target is searched first;
    then the costly start lands at the first target (y = 0.5 to 1e-12). Where a regular
    start reaches the family, the costly one is never called."""
    problem = Quartic()
    options = FamilyOptions()
    us, recs, guard = _quartic_branch(problem)
    costly = _Costly(-0.22)
    u, *_, target, _ = search_beyond(problem, guard, us, recs, options=options, amplitude_max=1.7,
                                     newton_tol=1e-12, max_newton=10, monitor=lambda p, v: p.monitor(v),
                                     starts=costly)
    first = 1.5 * (1 + options.jump_step)
    assert target == pytest.approx(first, rel=1e-15) and costly.calls == [target]
    assert abs(u[1] - 0.5) < 1e-12
    costly = _Costly(-0.22, 0.45)
    search_beyond(problem, guard, us, recs, options=options, amplitude_max=1.7, newton_tol=1e-12,
                  max_newton=10, monitor=lambda p, v: p.monitor(v), starts=costly)
    assert costly.calls == []


class _TwoFamilyOrbits(Quartic):
    """Quartic's roots and a fifth, y = 0.8 (share 0.85): two orbits of the family at every
    amplitude, y = 0.5 (share 0.7) and y = 0.8."""

    ROOTS = (-0.3, -0.2, -0.1, 0.5, 0.8)


@pytest.mark.parametrize("order", [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)])
def test_the_landing_does_not_depend_on_the_order_of_the_starts(order):
    """Starts by the three orbits off the family (y = −0.22), by y = 0.5 (0.45) and by
    y = 0.8 (0.85), in every order: each start deflates only the orbits it reached, every
    start runs, so the first target yields the same orbits and the landing is the one of
    larger share, y = 0.8 (to 1e-12, Newton's tolerance on a simple root)."""
    problem = _TwoFamilyOrbits()
    options = FamilyOptions()
    us, recs, guard = _quartic_branch(problem)
    ys = np.array([-0.22, 0.45, 0.85])[list(order)]
    u, _, _, rec, _, target, _ = search_beyond(
        problem, guard, us, recs, options=options, amplitude_max=2.5, newton_tol=1e-12, max_newton=10,
        monitor=lambda p, v: p.monitor(v), starts=_Starts(*ys))
    assert target == pytest.approx(1.5 * (1 + options.jump_step), rel=1e-15)
    assert abs(u[1] - 0.8) < 1e-12 and abs(rec["fundamental_share"] - 0.85) < 1e-12
