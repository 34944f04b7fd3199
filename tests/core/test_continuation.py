"""The path follower on problems with known answers, and its failure behaviour."""

import math

import numpy as np
import pytest
import scipy.sparse as sp

from mmshbm.core.continuation import ContinuationOptions, continue_branch


class Circle:
    """x² + y² = ρ² in (x, y): one equation, two unknowns; folds in y at x = ±ρ."""

    n_unknowns = 2

    def __init__(self, radius=1.0, sparse=False, wall=None):
        self.radius, self.sparse, self.wall = radius, sparse, wall
        self.evaluations = 0

    def evaluate(self, u, jacobian=True):
        self.evaluations += 1
        if self.wall is not None and u[0] > self.wall:
            raise ArithmeticError("beyond the wall")
        R = np.array([u @ u - self.radius**2])
        if not jacobian:
            return R
        J = 2 * u[None, :]
        return R, (sp.csr_matrix(J) if self.sparse else J)

    def monitor(self, u):
        return {"x": float(u[0]), "y": float(u[1])}


@pytest.mark.parametrize("sparse", [False, True])
def test_follows_a_circle_and_stops_on_a_bound(sparse):
    p = Circle(sparse=sparse)
    res = continue_branch(p, np.array([0.0, -1.0]), np.array([1.0, 0.0]),
                          ContinuationOptions(ds=0.1, ds_max=0.3, bounds={"x": (-0.5, 2.0)}))
    radius = np.hypot(res.u[:, 0], res.u[:, 1])
    np.testing.assert_allclose(radius, 1.0, atol=1e-10)
    # counter-clockwise from the bottom, over the top (a fold: dy/ds = x changes sign
    # there) down to x = -0.5 on the upper half
    assert res.status == "bound:x"
    assert res.records["x"][-1] == pytest.approx(-0.5, abs=1e-9)
    assert res.records["y"][-1] > 0
    folds = [i for name, i in res.special_points if name == "fold"]
    assert len(folds) == 1
    assert res.records["x"][folds[0] - 1] > 0 > res.records["x"][folds[0]]
    assert res.special_points[-1] == ("endpoint", len(res.u) - 1)
    assert len(res.residual_histories) == len(res.u)


def test_step_grows_when_newton_is_easy():
    res = continue_branch(Circle(radius=100.0), np.array([0.0, -100.0]), np.array([1.0, 0.0]),
                          ContinuationOptions(ds=0.01, ds_max=5.0, max_steps=40))
    assert res.status == "max_steps"
    assert res.step_size[-1] > 10 * res.step_size[1]


def test_failure_halves_the_step_and_keeps_every_point():
    p = Circle(wall=0.6)
    res = continue_branch(p, np.array([0.0, -1.0]), np.array([1.0, 0.0]),
                          ContinuationOptions(ds=0.2, ds_min=1e-4, max_steps=100))
    assert res.status.startswith("ds_min")
    assert "beyond the wall" in res.status
    assert len(res.u) >= 3
    assert res.records["x"][-1] <= 0.6
    assert res.records["x"][-1] > 0.6 - 1e-3  # it crept up to the wall by halving
    np.testing.assert_allclose(np.hypot(*res.u.T), 1.0, atol=1e-10)


def test_interrupt_returns_the_points_so_far():
    seen = []

    def callback(u, rec):
        seen.append(u)
        if len(seen) == 5:
            raise KeyboardInterrupt

    res = continue_branch(Circle(), np.array([0.0, -1.0]), np.array([1.0, 0.0]), callback=callback)
    assert res.status == "interrupted"
    assert len(res.u) == 5


def test_a_nested_continuation_lets_the_interrupt_through():
    """A continuation run inside another's step (a jump's backfill) must not turn the
    user's Ctrl-C into a status of its own: the outer run would go on to its end."""
    class Interrupting(Circle):
        def monitor(self, u):
            if u[0] > 0.5:
                raise KeyboardInterrupt
            return super().monitor(u)

    with pytest.raises(KeyboardInterrupt):
        continue_branch(Interrupting(), np.array([0.0, -1.0]), np.array([1.0, 0.0]), catch_interrupt=False)
    res = continue_branch(Interrupting(), np.array([0.0, -1.0]), np.array([1.0, 0.0]))
    assert res.status == "interrupted" and res.records["x"][-1] <= 0.5


def test_start_failure_is_a_status_not_an_exception():
    res = continue_branch(Circle(wall=-1.0), np.array([0.0, -1.0]), np.array([1.0, 0.0]))
    assert res.status.startswith("start failed")
    assert len(res.u) == 0


@pytest.mark.parametrize("kwargs, match", [
    ({"ds": -1.0}, "ds must be positive"),
    ({"ds": 3.0, "ds_max": 2.0}, "ds_min <= ds <= ds_max"),
    ({"max_steps": 0}, "max_steps must be >= 1"),
    ({"max_newton": 2.5}, "max_newton must be an integer"),
    ({"newton_tol": float("nan")}, "newton_tol must be finite"),
    ({"max_angle": 4.0}, "max_angle must be <= pi"),
    ({"branch_point_ds": 0.0}, "branch_point_ds must be positive"),
    ({"bounds": {"amplitude": (1.0, 0.5)}}, "lo < hi"),
    ({"bounds": {"amplitude": 3.0}}, "pair"),
])
def test_options_are_validated(kwargs, match):
    with pytest.raises((ValueError, TypeError), match=match):
        ContinuationOptions(**kwargs)


def test_angle_guard_rejects_jumps():
    opts = ContinuationOptions(ds=0.5, max_angle=math.radians(5), ds_max=0.5, max_steps=20, corner_ds=1e-6)
    res = continue_branch(Circle(), np.array([0.0, -1.0]), np.array([1.0, 0.0]), opts)
    # consecutive tangents on a unit circle differ by the arc angle = step length
    assert np.all(res.step_size[1:] <= math.radians(5) * 1.01)


class Pitchfork:
    """x (λ − x²) = 0 in (x, λ): the branch x = 0 meets x² = λ at a branch point at λ = 0,
    where det [J; t] = λ (on x = 0, t = (0, 1)) changes sign."""

    n_unknowns = 2

    def evaluate(self, u, jacobian=True):
        x, lam = u
        R = np.array([x * (lam - x * x)])
        if not jacobian:
            return R
        return R, np.array([[lam - 3 * x * x, x]])

    def monitor(self, u):
        return {"x": float(u[0]), "lam": float(u[1])}


@pytest.mark.parametrize("limit", [None, 1e-3, 1e-5])
def test_a_branch_point_is_kept_on_a_step_of_at_most_branch_point_ds(limit):
    """A sign change of det [J; t] is accepted on the step that finds it (None), or after
    the step has been halved down to ``branch_point_ds``: the branch point stays on the
    branch, bracketed by the points on either side to within that step."""
    res = continue_branch(Pitchfork(), np.array([0.0, -1.0]), np.array([0.0, 1.0]),
                          ContinuationOptions(ds=0.1, ds_max=0.3, branch_point_ds=limit,
                                              bounds={"lam": (-2.0, 1.0)}))
    assert res.status == "bound:lam"
    assert np.all(res.u[:, 0] == 0.0)  # the trivial branch throughout
    points = [i for name, i in res.special_points if name == "branch_point"]
    assert len(points) == 1
    before, after = res.u[points[0] - 1, 1], res.u[points[0], 1]
    assert before < 0.0 < after
    assert after - before <= (0.3 if limit is None else limit) * (1 + 1e-12)  # 0.3: ds_max


def test_a_branch_starting_just_below_a_bound_lands_on_it():
    # the previous point 1e-12 below the bound x = 0.5: the secant's root lies at s ≈ 1e-12 of the
    # step; the point returned is on the bound to the secant's criterion (1e-10 of the bound) and the
    # corrector's tolerance (1e-10 on x² + y² − 1, so ~1e-10 in x): 1e-9 holds both with room (a floor
    # on s of 1e-3 of the step overshot by 1e-4·dx/ds ≈ 9e-5)
    x0 = 0.5 - 1e-12
    res = continue_branch(Circle(), np.array([x0, -math.sqrt(1 - x0**2)]), np.array([1.0, 0.0]),
                          ContinuationOptions(ds=0.1, ds_max=0.3, bounds={"x": (-2.0, 0.5)}))
    assert res.status == "bound:x" and len(res.u) == 2
    assert res.records["x"][-1] == pytest.approx(0.5, abs=1e-9)
