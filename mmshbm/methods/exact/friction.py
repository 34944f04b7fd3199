"""Exact (event-driven) forced responses with one Coulomb friction contact.

The structure of :class:`~mmshbm.model.Model` with viscous damping C on the DOFs with
mass l, a harmonic force on them and one friction contact with constant slip force
s = μN on the massless DOF t (no unilateral contact). With the support's force g on the
node (g = −f, f the force the node exerts on the support) the massless DOFs are static,

    q_c = K_cc⁻¹ (e_t g − K_cl q_l),    u = q_t = wᵀ q_l + g / k,
    w = −K_lc K_cc⁻¹ e_t,               k = 1 / (K_cc⁻¹)_tt,

(wᵀq_l is where the node would sit without friction, k its condensed stiffness), and
the DOFs with mass obey M q_l'' + C q_l' + K_red q_l = F(t) + w g, K_red = K_ll − K_lc K_cc⁻¹ K_cl.
Three phases, each linear with constant coefficients:

* **stick** at u_s: g = k (u_s − wᵀq_l), so M q_l'' + C q_l' + (K_red + k w wᵀ) q_l = F(t) + k u_s w;
  it holds while |g| < s and ends where |g| reaches s (g = −σ s starts slip σ);
* **slip σ = ±1** (u̇ has the sign σ): g = −σ s, M q_l'' + C q_l' + K_red q_l = F(t) − σ s w,
  u = wᵀq_l − σ s/k; it holds while σ wᵀq_l' > 0 and ends where the node's velocity
  wᵀq_l' vanishes (then it sticks at u_s = u: the stick force starts at −σs and, since
  σ wᵀq_l'' < 0 there, moves inward).

g is continuous at both switches, so q_l, q_l' and q_l'' are continuous. Each phase is
solved in closed form (particular harmonic + static solution plus the free motion by the
eigen-decomposition of the first-order matrix, the ``_Phase`` of
:mod:`mmshbm.methods.exact.forced`); the switching functions are affine in the state (the
stick force, or the node velocity), sampled on a fine step, local extrema refined, and
crossings polished by brentq to ~1e-15 relative in time. With s = 0 the node never
sticks: one free phase, no events.

Periodic responses. The state is (q_l, q_l', u) (u matters only in stick); the period
map is iterated a few periods (damping and friction draw the motion onto the attractor)
and the fixed point is then solved by Newton's method with a forward-difference Jacobian
of the exact map (the fixed point, not the Jacobian, sets the accuracy). A stuck orbit's
position u_s is history: the orbit found is the one reached from the guess (the default
guess sticks at u_s = 0, the symmetric position of a symmetric structure).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
from scipy.optimize import brentq

from ... import _validate as check
from .forced import _Phase, orbit_amplitude

__all__ = ["FrictionSystem", "FrictionOrbit", "friction_orbit"]

_RTOL = 4 * np.finfo(float).eps


class FrictionSystem:
    """The stick and slip phases of a forced model with one friction contact, at one Ω.

    Parameters
    ----------
    model : Model
        One friction contact with a constant normal load, no unilateral contact; damping
        optional.
    force : array_like (n_dof,) or Excitation
        F̂ (N) on the DOFs with mass: F(t) = Re(σ(Ω) F̂ e^{iΩt}).
    omega : float
        Ω (rad/s).
    samples_per_period : int
        Sampling of the switching functions per shortest participating period.
    """

    def __init__(self, model, force, omega: float, samples_per_period: int = 32):
        from ..mms.forced import Excitation, harmonic_force

        if len(model.friction) != 1 or model.contacts:
            raise NotImplementedError("the exact friction reference handles one friction contact and no "
                                      f"unilateral contact; the model has {len(model.friction)} and "
                                      f"{len(model.contacts)}")
        fc = model.friction[0]
        if fc.normal_load is None:
            raise NotImplementedError("the exact friction reference needs a constant normal_load")
        exc = force if isinstance(force, Excitation) else harmonic_force(model, force)
        self.model, self.excitation = model, exc
        self.omega = check.positive("omega", omega)
        self.period = 2 * np.pi / self.omega
        self.samples = check.integer("samples_per_period", samples_per_period, minimum=8)
        b = model.blocks
        M = b["M_ll"].toarray()
        C = b["C_ll"].toarray() if b["C_ll"] is not None else np.zeros_like(M)
        K_red = model.reduced_stiffness.toarray()
        K_red = 0.5 * (K_red + K_red.T)
        self.Kcc_inv = la.inv(b["K_cc"])
        self.K_cl = b["K_lc"].T
        self.it = int(np.searchsorted(model.c, fc.dof))
        self.w = -b["K_lc"] @ self.Kcc_inv[:, self.it]
        self.k = 1.0 / self.Kcc_inv[self.it, self.it]
        self.s = fc.slip_force
        sig, _ = exc.scale(self.omega)
        F_l = sig * exc.vector[model.l]
        self.F_l = F_l
        self.n_l = n = M.shape[0]
        self.C = C
        zero = np.zeros(n)
        w, k, s = self.w, self.k, self.s
        self.slip = {+1: _Phase("slip+", M, C, K_red, -s * w, F_l, self.omega, zero, 0.0),
                     -1: _Phase("slip-", M, C, K_red, s * w, F_l, self.omega, zero, 0.0)}
        K_stick = K_red + k * np.outer(w, w)
        self._stick_unit = _Phase("stick", M, C, K_stick, k * w, F_l, self.omega, zero, 0.0)

    # ------------------------------------------------------------------ phases
    def stick(self, u_s: float) -> _Phase:
        """The stick phase at u_s (its static part scales with u_s)."""
        ph = copy.copy(self._stick_unit)
        ph.z_s = u_s * self._stick_unit.z_s
        ph.u_s = u_s
        return ph

    def _switch_functions(self, ph, sigma):
        """(c (k, 2n), d (k,)): the phase holds while c·z + d > 0 for every row."""
        n, w, k, s = self.n_l, self.w, self.k, self.s
        if sigma == 0:  # stick: s − g > 0 and s + g > 0, g = k(u_s − wᵀq)
            c = np.array([np.concatenate([k * w, np.zeros(n)]), np.concatenate([-k * w, np.zeros(n)])])
            return c, np.array([s - k * ph.u_s, s + k * ph.u_s])
        return np.array([np.concatenate([np.zeros(n), sigma * w])]), np.array([0.0])

    def classify(self, z: np.ndarray, u: float) -> tuple[int, float]:
        """(σ, u) of a state: σ = 0 stick at u, ±1 slip (u then follows from q_l)."""
        n = self.n_l
        q, v = z[:n], z[n:]
        if self.s == 0.0:
            return (1 if self.w @ v >= 0 else -1), float(self.w @ q)
        g = self.k * (u - self.w @ q)
        if abs(g) < self.s:
            return 0, u
        sigma = -1 if g > 0 else 1
        u_slip = float(self.w @ q - sigma * self.s / self.k)
        if sigma * (self.w @ v) > 0:
            return sigma, u_slip
        return 0, u_slip

    # ------------------------------------------------------------------ events
    def _first_switch(self, ph, alpha, t0, t_end, c, d, just_switched):
        """Earliest (t, row) in (t0, t_end] where a switching function c·z + d goes below
        zero, or (None, -1)."""
        amp = np.abs(c @ ph.V) * np.abs(alpha)[None, :]
        forced = np.abs(c @ ph.z_hat)
        scale = np.abs(d) + np.abs(c) @ (np.abs(ph.z_s) + np.abs(ph.z_hat)) + amp.sum(axis=1)
        tol = 1e-12 * scale
        keep = amp.max(axis=0) > 1e-15 * max(scale.max(), 1e-300)
        lam_abs = np.abs(ph.lam[keep])
        w_max = max(float(lam_abs.max()) if lam_abs.size else 0.0, self.omega)
        dt = 2 * np.pi / w_max / self.samples
        n_int = max(1, math.ceil((t_end - t0) / dt))
        t = t0 + (t_end - t0) * np.arange(n_int + 1) / n_int
        dt = (t_end - t0) / n_int
        dip = dt**2 / 8 * (amp @ (np.abs(ph.lam) ** 2) + forced * self.omega**2)
        Z = ph.state(alpha, t0, t)
        U = c @ Z + d[:, None]
        Zd = self._rate(ph, alpha, t0, t)
        D = c @ Zd
        best, row = None, -1
        xtol = 1e-17 * self.period
        for r in range(c.shape[0]):

            def u(tt, r=r):
                return float(c[r] @ ph.state(alpha, t0, tt) + d[r])

            def du(tt, r=r):
                return float(c[r] @ self._rate(ph, alpha, t0, tt))

            Ur = U[r].copy()
            if just_switched:
                Ur[0] = max(Ur[0], 0.0)
            hit = None
            for i in range(n_int):
                if best is not None and t[i] >= best:
                    break
                if Ur[i + 1] < -tol[r]:
                    if u(t[i]) > 0:
                        hit = brentq(u, t[i], t[i + 1], xtol=xtol, rtol=_RTOL)
                    elif D[r, i] > 0 > D[r, i + 1]:  # starts on zero, rises, then falls
                        tm = brentq(du, t[i], t[i + 1], xtol=xtol, rtol=_RTOL)
                        hit = brentq(u, tm, t[i + 1], xtol=xtol, rtol=_RTOL) if u(tm) > 0 else t[i]
                    else:
                        hit = t[i]
                    break
                if D[r, i] < 0 < D[r, i + 1] and min(Ur[i], Ur[i + 1]) - dip[r] < tol[r]:
                    tm = brentq(du, t[i], t[i + 1], xtol=xtol, rtol=_RTOL)
                    if u(tm) < -tol[r]:
                        lo = t[i] if u(t[i]) > 0 else None
                        hit = brentq(u, lo, tm, xtol=xtol, rtol=_RTOL) if lo is not None else t[i]
                        break
            if hit is not None and (best is None or hit < best):
                best, row = hit, r
        return best, row

    @staticmethod
    def _rate(ph, alpha, t0, t):
        """ż(t) of the phase's closed-form solution; t scalar -> (2n,), array -> (2n, n_t)."""
        t = np.asarray(t, dtype=float)
        E = np.exp(np.multiply.outer(ph.lam, t - t0))
        _, dzp = ph.particular(t)
        return dzp + (ph.V @ ((alpha * ph.lam).reshape((-1,) + (1,) * t.ndim) * E)).real

    # ------------------------------------------------------------------ motion
    def integrate(self, z0, u0: float, t0: float = 0.0, duration: float | None = None,
                  max_events: int = 10_000):
        """Exact motion from (z(t₀), u(t₀)) = (z0, u0) over ``duration`` (default a period).

        Returns
        -------
        segments : list of (phase, σ, t_start, t_end, α); σ = 0 stick (``phase.u_s``), ±1 slip
        z_end : ndarray (2 n_l,)
        u_end : float
        """
        z = np.asarray(z0, dtype=float).copy()
        t_end = t0 + (self.period if duration is None else duration)
        sigma, u = self.classify(z, float(u0))
        t, segments, just = t0, [], False
        for _ in range(max_events):
            ph = self.stick(u) if sigma == 0 else self.slip[sigma]
            alpha = ph.modal(z, t)
            if self.s == 0.0:
                t_sw, row = None, -1
            else:
                c, d = self._switch_functions(ph, sigma)
                t_sw, row = self._first_switch(ph, alpha, t, t_end, c, d, just)
            stop = t_end if t_sw is None else t_sw
            segments.append((ph, sigma, t, stop, alpha))
            z = ph.state(alpha, t, stop)
            if sigma != 0:
                u = float(self.w @ z[:self.n_l] - sigma * self.s / self.k)
            if t_sw is None:
                return segments, z, u
            t, just = stop, True
            sigma = (-1 if row == 0 else 1) if sigma == 0 else 0
        raise RuntimeError(f"more than {max_events} stick-slip switches in one period")

    def period_map(self, y: np.ndarray) -> np.ndarray:
        """(z(T), u(T)) from y = (z(0), u(0))."""
        _, z, u = self.integrate(y[:-1], y[-1])
        return np.concatenate([z, [u]])


@dataclass(frozen=True, eq=False)
class FrictionOrbit:
    """A periodic forced response with one friction contact, exact to round-off.

    Attributes
    ----------
    frequency : float
        Excitation frequency (Hz).
    y0 : ndarray (2 n_l + 1,)
        (q_l, q_l', u) at t = 0.
    converged : bool
    iterations : int
        Newton iterations.
    residual : float
        max |y(T) − y(0)| relative to the state's scale.
    system : FrictionSystem
    segments : list
        (phase, σ, t_start, t_end, α) over [0, T].
    """

    frequency: float
    y0: np.ndarray
    converged: bool
    iterations: int
    residual: float
    system: FrictionSystem
    segments: list

    @property
    def switch_times(self) -> np.ndarray:
        """Times (s) in (0, T) where the node switches between stick and slip."""
        return np.array([seg[2] for seg in self.segments[1:]])

    @property
    def slip_fraction(self) -> float:
        """Fraction of the period the node slips."""
        return sum(b - a for _, sg, a, b, _ in self.segments if sg != 0) / self.system.period

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """At times t in [0, T]: all DOFs q (n_dof, n_t), velocities of the DOFs with mass
        (n_l, n_t) and the force the node exerts on the support f (n_t,) (N)."""
        sysm = self.system
        t = np.atleast_1d(np.asarray(t, dtype=float))
        n = sysm.n_l
        Z = np.empty((2 * n, t.size))
        g = np.empty(t.size)
        for ph, sg, a, b, alpha in self.segments:
            m = (t >= a) & (t <= b)
            if m.any():
                Z[:, m] = ph.state(alpha, a, t[m])
                g[m] = -sg * sysm.s if sg != 0 else sysm.k * (ph.u_s - sysm.w @ Z[:n, m])
        model = sysm.model
        q = np.empty((model.n_dof, t.size))
        q[model.l] = Z[:n]
        e = np.zeros(len(model.c))
        e[sysm.it] = 1.0
        q[model.c] = sysm.Kcc_inv @ (np.outer(e, g) - sysm.K_cl @ Z[:n])
        return q, Z[n:], -g

    def _quadrature(self, nodes: int = 32):
        """Gauss–Legendre nodes and weights (t, wt) over [0, T], each segment split into
        pieces of at most an eighth of the shortest participating period."""
        x, w = np.polynomial.legendre.leggauss(nodes)
        sysm = self.system
        ts, ws = [], []
        for ph, _, a, b, _ in self.segments:
            if b <= a:
                continue
            fastest = max(float(np.abs(ph.lam).max()), sysm.omega)
            n_sub = max(1, math.ceil((b - a) * fastest / (np.pi / 4)))
            edges = np.linspace(a, b, n_sub + 1)
            for lo, hi in zip(edges[:-1], edges[1:], strict=True):
                ts.append(0.5 * (hi - lo) * x + 0.5 * (hi + lo))
                ws.append(0.5 * (hi - lo) * w)
        return np.concatenate(ts), np.concatenate(ws)

    def fourier(self, dof: int, harmonics: int) -> np.ndarray:
        """NLvib-ordered Fourier coefficients (2H+1,) of q[dof](τ), τ = Ω t (quadrature on
        the smooth pieces: exact to round-off)."""
        t, wt = self._quadrature()
        q = self.evaluate(t)[0][dof]
        om = self.system.omega
        k = np.arange(1, harmonics + 1)
        out = np.empty(2 * harmonics + 1)
        out[0] = (wt * q).sum() / self.system.period
        out[1::2] = np.cos(np.outer(k, om * t)) @ (wt * q) * 2 / self.system.period
        out[2::2] = np.sin(np.outer(k, om * t)) @ (wt * q) * 2 / self.system.period
        return out

    def energy_balance(self) -> dict:
        """Work per period (J): ``input`` ∮ Fᵀq_l' dt, ``viscous`` ∮ q_l'ᵀ C q_l' dt and
        ``friction`` s·Σ|Δu| over the slip phases (= ∮ f u̇ dt, u̇ of one sign in a slip)."""
        sysm = self.system
        t, wt = self._quadrature()
        _, v, _ = self.evaluate(t)
        F = (np.outer(sysm.F_l, np.exp(1j * sysm.omega * t))).real
        inp = float(np.einsum("it,it,t->", F, v, wt))
        visc = float(np.einsum("it,ij,jt,t->", v, sysm.C, v, wt))
        fric = 0.0
        for ph, sg, a, b, alpha in self.segments:
            if sg != 0:
                za, zb = ph.state(alpha, a, a), ph.state(alpha, a, b)
                fric += sysm.s * abs(sysm.w @ (zb[:sysm.n_l] - za[:sysm.n_l]))
        return {"input": inp, "viscous": visc, "friction": fric}

    def amplitude(self, dof: int | None = None, n: int = 4096) -> float:
        """Largest |q[dof]| over the period (m), refined around the sampled peak."""
        return orbit_amplitude(self, dof, n)


def friction_orbit(model, force, frequency: float, guess=None, *, tol: float = 1e-12, max_iter: int = 40,
                   settle_periods: int = 3, samples_per_period: int = 32) -> FrictionOrbit:
    """The periodic response of period 1/``frequency`` with one friction contact.

    Parameters
    ----------
    model : Model
        One friction contact (constant normal load), no unilateral contact.
    force : array_like (n_dof,) or Excitation
    frequency : float
        Excitation frequency (Hz).
    guess : ndarray (2 n_l + 1,), optional
        (q_l(0), q_l'(0), u(0)); default the stuck linear response at u_s = 0.
    tol : float
        On max |y(T) − y(0)| relative to the state's scale.
    settle_periods : int
        Periods integrated from the guess before Newton.

    Returns
    -------
    FrictionOrbit
        Check ``converged``.
    """
    omega = 2 * np.pi * check.positive("frequency", frequency)
    sysm = FrictionSystem(model, force, omega, samples_per_period)
    n = sysm.n_l
    if guess is None:
        y = np.concatenate([sysm.stick(0.0).particular(0.0)[0], [0.0]])
    else:
        y = np.asarray(guess, dtype=float).copy()
        if y.shape != (2 * n + 1,):
            raise ValueError(f"guess must have shape ({2 * n + 1},), got {y.shape}")
    for _ in range(settle_periods):
        y = sysm.period_map(y)

    y, converged, it, res = periodic_state(sysm.period_map, y, n, omega, tol, max_iter)
    segments, _, _ = sysm.integrate(y[:-1], y[-1])
    return FrictionOrbit(omega / (2 * np.pi), y, converged, it, res, sysm, segments)


def periodic_state(period_map, y, n: int, omega: float, tol: float, max_iter: int):
    """Newton on period_map(y) − y = 0 for a friction orbit's state y = (q (n,), q′ (n,), u)
    (displacements scaled by their largest entry, velocities by that times Ω, ``omega``
    rad/s). The Jacobian by forward differences of the period map (step 1e-7 of each
    scale), least-squares steps clipped to one scale. Returns (y, converged, iterations,
    the last scaled residual)."""
    def scales(y):
        q = max(float(np.abs(y[:n]).max()), abs(y[-1]), 1e-300)
        v = max(float(np.abs(y[n:2 * n]).max()), q * omega)
        return np.concatenate([np.full(n, q), np.full(n, v), [q]])

    converged, res, it = False, np.inf, 0
    for it in range(1, max_iter + 1):  # noqa: B007 - the count is reported
        sc = scales(y)
        r = period_map(y) - y
        res = float(np.abs(r / sc).max())
        if res <= tol:
            converged = True
            break
        J = np.empty((2 * n + 1, 2 * n + 1))
        base = r + y
        for j in range(2 * n + 1):
            h = 1e-7 * sc[j]
            e = y.copy()
            e[j] += h
            J[:, j] = (period_map(e) - base) / h
        J -= np.eye(2 * n + 1)
        dy = np.linalg.lstsq(J, -r, rcond=None)[0]
        big = float(np.abs(dy / sc).max())
        if big > 1.0:
            dy /= big
        y = y + dy
    return y, converged, it, res
