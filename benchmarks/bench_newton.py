"""One Newton iteration (residual, Jacobian, bordered solve) and one whole corrector step
per method. Models and points are built in ``setup``; kernels are compiled there."""

from __future__ import annotations

import numpy as np

from benchmarks.common import HARMONICS, STEPS, backbone, check_feasible, model, options, point_near, warm_up

NEWTON_MODELS = ("oscillator", "beam8", "beam21", "beam100", "beam1000")
CORRECTOR_MODELS = ("oscillator", "beam8", "beam21")


def _iteration_setup(self, name, method, harmonics=None, steps=None):
    from mmshbm.methods.registry import make_problem

    check_feasible(name, method, harmonics, single_iteration=True)
    warm_up(method)
    m = model(name)
    self.problem = make_problem(m, method, **options(method, harmonics, steps))
    self.u = self.problem.linear_point(1.5 * m.gap)
    self.t = self.problem.initial_tangent()
    self.iterate()  # first call: plans, caches, compilation


def _iterate(self):
    from mmshbm.core.bordered import bordered_solve as _bordered_solve

    # alternate two states whose last unknown (Ω) differs in the last digits: MMS-HBM
    # reuses its condensation at an unchanged Ω, and a Newton iteration always changes Ω
    self.calls = getattr(self, "calls", 0) + 1
    u = self.u.copy()
    if self.calls % 2:
        u[-1] *= 1 + 1e-12
    R, J = self.problem.evaluate(u, jacobian=True)
    return _bordered_solve(J, self.t, np.append(R, 0.0))


class NewtonIteration:
    """Harmonic-balance methods: evaluate R and J at 1.5 gaps, then solve [J; tᵀ] du = [R; 0]."""

    params = [("mmshbm", "penalty"), NEWTON_MODELS, HARMONICS]
    param_names = ["method", "model", "H"]
    timeout = 300

    def setup(self, method, name, H):
        _iteration_setup(self, name, method, harmonics=H)

    iterate = _iterate

    def time_newton_iteration(self, method, name, H):
        self.iterate()


class ShootingNewtonIteration:
    """Shooting: integrate half a period with n_l + 1 tangent vectors, then the bordered solve."""

    params = [("oscillator", "beam8", "beam21", "beam100"), STEPS]
    param_names = ["model", "steps"]
    timeout = 300

    def setup(self, name, steps):
        _iteration_setup(self, name, "shooting", steps=steps)

    iterate = _iterate

    def time_newton_iteration(self, name, steps):
        self.iterate()


def _corrector_setup(self, name, method, harmonics=None, steps=None):
    """A secant predictor between two converged points above grazing; the timed corrector
    converges from it to the second point."""
    from mmshbm.core.continuation import ContinuationOptions

    check_feasible(name, method, harmonics)
    warm_up(method)
    m = model(name)
    branch = backbone(name, method, harmonics, steps, amplitude_gaps=1.5)
    above = np.flatnonzero(branch.amplitude > 1.05 * m.gap)
    if len(above) < 2:
        raise NotImplementedError(f"{method} branch does not pass 1.05 gaps here ({branch.status})")
    i = min(point_near(branch, 1.2 * m.gap), above[-2])
    i = max(i, above[0])
    u0, u1 = branch.states[i], branch.states[i + 1]
    ds = float(np.linalg.norm(u1 - u0))
    self.t = (u1 - u0) / ds
    # predictor: half a step beyond u0 along the secant, then slightly off it
    self.u_pred = u0 + 0.5 * ds * self.t
    self.problem = branch.solver
    opts = ContinuationOptions()
    self.tol, self.max_newton, self.step_tol = opts.newton_tol, 2 * opts.max_newton, opts.step_tol
    self.correct()


def _correct(self):
    from mmshbm.core.continuation import newton

    return newton(self.problem, self.u_pred, self.t, self.u_pred, self.tol, self.max_newton, self.step_tol)


class CorrectorStep:
    """One pseudo-arclength corrector (Newton to convergence) near 1.2 gaps."""

    params = [("mmshbm", "penalty"), CORRECTOR_MODELS, HARMONICS]
    param_names = ["method", "model", "H"]
    timeout = 300

    def setup(self, method, name, H):
        _corrector_setup(self, name, method, harmonics=H)

    correct = _correct

    def time_corrector(self, method, name, H):
        self.correct()


class ShootingCorrectorStep:
    """Shooting's corrector near 1.2 gaps."""

    params = [CORRECTOR_MODELS, STEPS]
    param_names = ["model", "steps"]
    timeout = 300

    def setup(self, name, steps):
        _corrector_setup(self, name, "shooting", steps=steps)

    correct = _correct

    def time_corrector(self, name, steps):
        self.correct()
