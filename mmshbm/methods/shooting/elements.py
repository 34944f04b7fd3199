"""Baseline: shooting on the backbone of a model with elements (no stops).

The time-domain counterpart of the element path of MMS-HBM (:mod:`mmshbm.methods.mms.smooth`):
the full model with its elements,

    M_ll q_l'' + g_l(q) = 0,    g_c(q) = 0,     g(q) = K q + Σ w φ(wᵀ q_e),

(the massless DOFs c follow the others statically, through the elements too), is
integrated by the trapezoidal rule (Newmark average acceleration, implicit, A-stable,
time-reversible, order 2): each step solves

    M_ll [(4/h²)(q1_l − q0_l − h v0) − a0] + g_l(q1) = 0,    g_c(q1) = 0

for q1 by Newton (dense, the tangent (4/h²) M + K + ∂f/∂q), then a1 = −M_ll⁻¹ g_l(q1),
v1 = v0 + h (a0 + a1)/2. As for shooting on stops (:mod:`mmshbm.methods.shooting.conservative`)
the nonlinear modes are symmetric orbits: the unknowns are the positions x = q_l(0) of the
DOFs with mass and Ω (the period T = 2π/Ω), the velocities vanish at t = 0, and the
equations are v_l(T/2) = 0 after N/2 steps (n_l equations in n_l + 1 unknowns, regular
along the family). The Jacobian comes from the step's sensitivities to (x, h) carried
along (the implicit function theorem on each step), h = T/N. The frequency error of the
rule is ≈ (ω h)²/12 per resolved harmonic ω.
"""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...core.problem import BackboneProblemBase, OneEvaluation
from ...model.linear_modes import amplitude_mode
from ...model.model import Model
from ..mms.set_condense import SetCondensation
from ..mms.smooth import element_length

__all__ = ["ElementShootingProblem"]

#: Newton iterations per step, and the step's relative tolerance on q
_STEP_ITER, _STEP_TOL = 30, 1e-13


class ElementShootingProblem(OneEvaluation, BackboneProblemBase):
    """Half-period shooting of a model with elements (module docstring).

    Parameters
    ----------
    model : Model
        With elements, no stops, no friction.
    steps_per_period : int
        N (even, >= 16): trapezoidal steps per period.
    mode : int
        The linear mode (1-based) the branch starts from.
    """

    method = "shooting"
    setting_names = ("mode", "steps_per_period")

    def __init__(self, model: Model, steps_per_period: int = 512, mode: int = 1):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        if not model.elements:
            raise ValueError("the model has no elements: use ShootingProblem")
        if model.contacts or model.friction:
            raise NotImplementedError("method 'shooting' takes elements only on models without stops or "
                                      "friction contacts: use method 'mmshbm' for elements beside stops")
        self.model = model
        self.steps_per_period = check.integer("steps_per_period", steps_per_period, minimum=16)
        if self.steps_per_period % 2:
            raise ValueError(f"steps_per_period must be even (the orbit is shot over half a period), "
                             f"got {steps_per_period}")
        self.mode = check.integer("mode", mode, minimum=1)
        if self.mode > len(model.l):
            raise ValueError(f"mode must be <= the number of DOFs with mass ({len(model.l)}), "
                             f"got {self.mode}")
        self.l, self.c = model.l, model.c
        self.n, self.n_l = model.n_dof, len(model.l)
        self.K = model.K.toarray()
        self.M_ll = model.M.toarray()[np.ix_(self.l, self.l)]
        self.M_ll_inv = np.linalg.inv(self.M_ll)
        self.elements = model.elements
        self.linear_frequency, self.mode_shape = amplitude_mode(model, self.mode)
        self.omega_ref = 2 * np.pi * self.linear_frequency
        self.amplitude_dof = int(model.amplitude_dof)
        dofs = sorted({d for e in model.elements for d in e.dofs})
        D0 = SetCondensation(model, dofs).dynamic_stiffness(0.0, 0, derivative=False)[0][0]
        length = element_length(model, D0, np.array(dofs))
        shape = np.abs(self.mode_shape[self.l])
        self.xscale = length * np.maximum(shape, 1e-3 * shape.max())
        self.colscale = np.concatenate([self.xscale, [self.omega_ref]])
        self.rowscale = self.omega_ref * self.xscale
        self.n_unknowns = self.n_l + 1
        self._last = None  # (u, orbit) of the last evaluation
        self.evaluations = 0

    # ------------------------------------------------------------------ the force
    def _force(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(g(q) = K q + the elements' force (n,), its tangent ∂g/∂q (n, n))."""
        g = self.K @ q
        Kt = self.K.copy()
        for e in self.elements:
            dofs = list(e.dofs)
            f, df = e.sampled(q[dofs][:, None])
            g[dofs] += f[:, 0]
            Kt[np.ix_(dofs, dofs)] += df[:, :, 0]
        return g, Kt

    def _static(self, q: np.ndarray, scale: float) -> np.ndarray:
        """q with its massless DOFs solved from g_c(q) = 0 (Newton from the q given, to
        round-off of ``scale``, m)."""
        c = self.c
        if not len(c):
            return q
        q = q.copy()
        for _ in range(_STEP_ITER):
            g, Kt = self._force(q)
            dq = np.linalg.solve(Kt[np.ix_(c, c)], g[c])
            q[c] -= dq
            if np.abs(dq).max() <= _STEP_TOL * scale:
                return q
        raise ArithmeticError("the massless DOFs' static equations did not converge")

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Scaled unknowns -> (x = q_l(0) (n_l,) m/rad, Ω rad/s)."""
        if np.shape(u) != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {np.shape(u)}")
        y = np.asarray(u, dtype=float) * self.colscale
        return y[:-1], float(y[-1])

    def pack(self, x: np.ndarray, omega: float) -> np.ndarray:
        return np.concatenate([np.asarray(x, dtype=float), [omega]]) / self.colscale

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        return self.pack(amplitude * self.mode_shape[self.l], self.omega_ref)

    def initial_tangent(self) -> np.ndarray:
        t = self.linear_mode_point(1.0)
        t[-1] = 0.0
        return t / np.linalg.norm(t)

    # ------------------------------------------------------------------ the orbit
    def orbit(self, x: np.ndarray, omega: float, sensitivities: bool = True):
        """Integrate half a period from (q_l = x, v = 0).

        Returns
        -------
        t : ndarray (N/2 + 1,)
            Instants (s).
        q : ndarray (N/2 + 1, n)
            Every DOF at them.
        v : ndarray (N/2 + 1, n_l)
            The velocities of the DOFs with mass.
        S : ndarray (n_l, n_l + 1) or None
            ∂v_l(T/2)/∂(x, Ω).
        """
        l, c, n_l = self.l, self.c, self.n_l
        N = self.steps_per_period
        h = 2 * np.pi / (omega * N)
        q = np.zeros(self.n)
        q[l] = x
        scale = max(float(np.abs(x).max()), 1e-300)  # the orbit's size: the steps' tolerance
        q = self._static(q, scale)
        g, Kt = self._force(q)
        a = -self.M_ll_inv @ g[l]
        v = np.zeros(n_l)
        n_p = n_l + 1  # sensitivity columns: x, h
        if sensitivities:
            Sq = np.zeros((self.n, n_p))
            Sq[l, :n_l] = np.eye(n_l)
            if len(c):
                Sq[c] = -np.linalg.solve(Kt[np.ix_(c, c)], Kt[np.ix_(c, l)] @ Sq[l])
            Sa = -self.M_ll_inv @ (Kt[l] @ Sq)
            Sv = np.zeros((n_l, n_p))
        qs, vs = [q.copy()], [v.copy()]
        mass = np.zeros((self.n, self.n))
        mass[np.ix_(l, l)] = (4.0 / h**2) * self.M_ll
        for _ in range(N // 2):
            q1 = q.copy()
            q1[l] = q[l] + h * v + 0.5 * h * h * a
            for _ in range(_STEP_ITER):
                g1, Kt1 = self._force(q1)
                r = g1.copy()
                r[l] += self.M_ll @ ((4.0 / h**2) * (q1[l] - q[l] - h * v) - a)
                A = mass + Kt1
                dq = np.linalg.solve(A, r)
                q1 -= dq
                if np.abs(dq).max() <= _STEP_TOL * scale:
                    break
            else:
                raise ArithmeticError(f"a trapezoidal step did not converge in {_STEP_ITER} iterations")
            g1, Kt1 = self._force(q1)
            a1 = -self.M_ll_inv @ g1[l]
            v1 = v + 0.5 * h * (a + a1)
            if sensitivities:
                # ∂r/∂(q0_l, v0, a0, h) · d(...) + A dq1 = 0 on the l rows (c rows: A dq1 = 0)
                rhs = np.zeros((self.n, n_p))
                rhs[l] = self.M_ll @ ((4.0 / h**2) * Sq[l] + (4.0 / h) * Sv + Sa)
                rhs[l, -1] -= self.M_ll @ (-(8.0 / h**3) * (q1[l] - q[l]) + (4.0 / h**2) * v)
                A = mass + Kt1
                Sq1 = np.linalg.solve(A, rhs)
                Sa1 = -self.M_ll_inv @ (Kt1[l] @ Sq1)
                Sv = Sv + 0.5 * h * (Sa + Sa1)
                Sv[:, -1] += 0.5 * (a + a1)
                Sq, Sa = Sq1, Sa1
            q, v, a = q1, v1, a1
            qs.append(q.copy())
            vs.append(v.copy())
        t = h * np.arange(N // 2 + 1)
        S = None
        if sensitivities:
            S = np.column_stack([Sv[:, :n_l], Sv[:, -1] * (-h / omega)])
        return t, np.array(qs), np.array(vs), S

    # ------------------------------------------------------------------ residual
    def _evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual v_l(T/2)/(ω_ref s) (n_l,) and, if asked, its Jacobian (n_l, n_l + 1)."""
        self.evaluations += 1
        x, omega = self.unpack(u)
        t, q, v, S = self.orbit(x, omega, jacobian)
        self._last = (np.array(u, dtype=float), (t, q, v))
        R = v[-1] / self.rowscale
        if not jacobian:
            return R
        return R, S * self.colscale[None, :] / self.rowscale[:, None]

    def monitor(self, u: np.ndarray) -> dict:
        """frequency (Hz), amplitude (m: the largest |q| of the amplitude DOF over the orbit,
        refined between steps by cubic Hermite interpolation), energy (J, at t = 0),
        contact_force_max (0: no stops)."""
        x, omega = self.unpack(u)
        last = self._last
        if last is not None and np.array_equal(last[0], u):
            t, q, v = last[1]
        else:
            t, q, v, _ = self.orbit(x, omega, sensitivities=False)
        q0 = q[0]
        energy = 0.5 * float(q0 @ (self.K @ q0)) + sum(
            float(e.potential(e.relative(q0[list(e.dofs)][:, None]))[0]) for e in self.elements)
        return {"frequency": omega / (2 * np.pi), "amplitude": self._peak(t, q, v), "energy": energy,
                "contact_force_max": 0.0}

    def _peak(self, t: np.ndarray, q: np.ndarray, v: np.ndarray) -> float:
        """max |q_amp(t)| over the half period (the other half mirrors it)."""
        d = self.amplitude_dof
        y = q[:, d]
        if d in set(self.l.tolist()):
            dy = v[:, list(self.l).index(d)]
        else:  # a massless DOF: its velocity from the differences of its positions
            dy = np.gradient(y, t)
        j = int(np.argmax(np.abs(y)))
        best = abs(y[j])
        for k in (j - 1, j):  # the intervals beside the best sample: Hermite cubic's extremum
            if k < 0 or k + 1 >= len(t):
                continue
            h = t[k + 1] - t[k]
            s = np.linspace(0.0, 1.0, 65)
            h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
            h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
            values = h00 * y[k] + h10 * h * dy[k] + h01 * y[k + 1] + h11 * h * dy[k + 1]
            best = max(best, float(np.abs(values).max()))
        return best
