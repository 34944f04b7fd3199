"""Exact (event-driven) forced, damped responses: the reference for the forced MMS-HBM.

With damping C on the DOFs with mass and a harmonic force F̂ on them, the massless
DOFs still follow statically (the damping does not touch them), so the motion of the
DOFs with mass is the continuous piecewise-linear system of :mod:`mmshbm.methods.exact`
plus damping and forcing. In each phase (open, closed) it is linear with constant
coefficients; in first-order form, z = (q_l, v_l),

    z' = A z + g + Re(b̂ e^{iΩt}),   A = [[0, I], [−M⁻¹K_s, −M⁻¹C]],
    g = [0; M⁻¹ f_s],   b̂ = [0; M⁻¹ σ(Ω) F̂_l],

with K_open = K_ll − K_lc K_cc⁻¹ K_cl, K_closed = K_open + k_c a aᵀ, f_open = 0,
f_closed = −k_c gap a (free gap h = gap + a·q_l, contact force λ = k_c max(0, −h); see
:class:`~mmshbm.methods.exact.system.PiecewiseLinearSystem`). Its solution is closed form:

    z(t) = z_s + Re(ẑ e^{iΩt}) + V e^{Λ(t − t₀)} V⁻¹ [z(t₀) − z_s − Re(ẑ e^{iΩt₀})],
    z_s = −A⁻¹ g,   ẑ = (iΩ I − A)⁻¹ b̂,   A = V Λ V⁻¹,

the particular solution of the harmonic forcing plus the free (decaying) motion. The
switching function (h in the open phase, λ in the closed one) is affine in z, hence a
sum of exponentials and one harmonic: it is sampled on a step of
1/``samples_per_period`` of the shortest participating period, local minima between
samples are refined, and crossings are polished by brentq to ~1e-15 relative in time.
Nothing jumps at a switch (no impulses: the node is massless), so the saltation
matrices are the identity and the monodromy is the ordered product of the phases'
e^{A Δt}.

Periodic responses (period 2π/Ω) solve z(T; z₀) − z₀ = 0 by Newton's method with the
exact Jacobian Φ(T) − I (:func:`forced_orbit`). Model: one contact, massless contact DOF
(as the rest of :mod:`mmshbm.methods.exact`); meant for small models (dense complex
eigen-decompositions of size 2 n_l).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
from scipy.optimize import brentq

from ... import _validate as check
from .system import PiecewiseLinearSystem

__all__ = ["ForcedSystem", "ForcedOrbit", "forced_orbit"]

_RTOL = 4 * np.finfo(float).eps


class _Phase:
    """One phase's closed-form solution (see the module docstring)."""

    def __init__(self, name, M, C, K, f_static, b_hat, omega, switch_grad, switch_offset):
        n = M.shape[0]
        Minv = np.linalg.inv(M)
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = -Minv @ K
        A[n:, n:] = -Minv @ C
        g = np.concatenate([np.zeros(n), Minv @ f_static])
        b = np.concatenate([np.zeros(n), Minv @ b_hat])
        self.name = name
        self.A = A
        self.lam, self.V = la.eig(A)
        self.Vinv = la.inv(self.V)
        self.z_s = -la.solve(A, g)
        self.z_hat = la.solve(1j * omega * np.eye(2 * n) - A, b)
        self.omega = omega
        # switching function u = c·z + d (positive while the phase holds)
        self.c = np.concatenate([switch_grad, np.zeros(n)])
        self.d = float(switch_offset)
        self.cV = self.c @ self.V

    def particular(self, t):
        """z_s + Re(ẑ e^{iΩt}) and its derivative; t scalar -> (2n,), array -> (2n, n_t)."""
        t = np.asarray(t, dtype=float)
        e = np.exp(1j * self.omega * t)
        zp = self.z_s.reshape((-1,) + (1,) * t.ndim) + (np.multiply.outer(self.z_hat, e)).real
        dzp = (np.multiply.outer(1j * self.omega * self.z_hat, e)).real
        return zp, dzp

    def modal(self, z0, t0):
        """Coefficients α = V⁻¹ (z(t₀) − z_p(t₀)) of the free part."""
        return self.Vinv @ (z0 - self.particular(t0)[0])

    def state(self, alpha, t0, t):
        """z(t) for the free coefficients α set at t₀; t scalar or (n_t,)."""
        t = np.asarray(t, dtype=float)
        E = np.exp(np.multiply.outer(self.lam, t - t0))
        zp, _ = self.particular(t)
        return zp + (self.V @ (alpha.reshape((-1,) + (1,) * t.ndim) * E)).real

    def transition(self, duration):
        return ((self.V * np.exp(self.lam * duration)) @ self.Vinv).real


class ForcedSystem:
    """Both phases of a damped, harmonically forced :class:`~mmshbm.model.Model` at one Ω.

    Parameters
    ----------
    model : Model
        One contact, massless contact DOF; damping optional.
    force : array_like (n_dof,) or Excitation
        F̂ (N) on the DOFs with mass.
    omega : float
        Excitation frequency Ω (rad/s).
    """

    def __init__(self, model, force, omega: float):
        from ..mms.forced import Excitation, harmonic_force

        self.base = PiecewiseLinearSystem.of(model)
        exc = force if isinstance(force, Excitation) else harmonic_force(model, force)
        if isinstance(force, Excitation):
            harmonic_force(model, force.vector)
        self.model = model
        self.excitation = exc
        self.omega = check.positive("omega", omega)
        b = model.blocks
        M = b["M_ll"].toarray()
        C = b["C_ll"].toarray() if b["C_ll"] is not None else np.zeros_like(M)
        K_open = model.reduced_stiffness.toarray()
        K_open = 0.5 * (K_open + K_open.T)
        a, kc, gap = self.base.gap_gradient, self.base.contact_stiffness, model.gap
        s, _ = exc.scale(self.omega)
        F_l = s * exc.vector[model.l]
        self.n_l = M.shape[0]
        self.open = _Phase("open", M, C, K_open, np.zeros(self.n_l), F_l, self.omega, a, gap)
        self.closed = _Phase("closed", M, C, K_open + kc * np.outer(a, a), -kc * gap * a, F_l, self.omega,
                             -kc * a, -kc * gap)
        self.period = 2 * np.pi / self.omega
        self._t_ref = self.period

    def phase_of(self, z) -> _Phase:
        """The phase a state starts in (by the free gap, then its rate)."""
        q, v = z[:self.n_l], z[self.n_l:]
        h = self.base.free_gap(q)
        scale = abs(self.model.gap) + float(np.abs(self.base.gap_gradient) @ np.abs(q))
        if abs(h) > 1e-12 * scale:
            return self.open if h > 0 else self.closed
        return self.open if self.base.gap_gradient @ v >= 0 else self.closed

    def _first_switch(self, ph: _Phase, alpha, t0, t_end, samples_per_period, just_switched):
        """First time in (t0, t_end] where ph's switching function u goes below zero, or None.

        u is sampled on a step of 1/samples_per_period of the shortest participating
        period; a sample below −tol brackets the crossing, and a local minimum between two
        samples (u' from − to +) that may dip below zero (bound dt²/8 max|u''|) is located
        by brentq on u' first. Crossings are polished by brentq."""
        amp = np.abs(ph.cV * alpha)
        forced = abs(ph.c @ ph.z_hat)
        scale = abs(ph.d) + float(np.abs(ph.c) @ (np.abs(ph.z_s) + np.abs(ph.z_hat))) + float(amp.sum())
        tol = 1e-12 * scale
        keep = amp > 1e-15 * scale
        w = np.abs(ph.lam[keep])
        w_max = max(float(w.max()) if w.size else 0.0, self.omega)
        dt = 2 * np.pi / w_max / samples_per_period
        n_int = max(1, math.ceil((t_end - t0) / dt))
        t = t0 + (t_end - t0) * np.arange(n_int + 1) / n_int
        dt = (t_end - t0) / n_int
        dip = dt**2 / 8 * (float(amp @ np.abs(ph.lam) ** 2) + forced * self.omega**2)
        n = self.n_l
        cv = np.concatenate([np.zeros(n), ph.c[:n]])  # u' = grad · v

        def u(tt):
            return float(ph.c @ ph.state(alpha, t0, tt) + ph.d)

        def du(tt):
            return float(cv @ ph.state(alpha, t0, tt))

        Z = ph.state(alpha, t0, t)
        U = ph.c @ Z + ph.d
        D = cv @ Z
        if just_switched:
            U[0] = max(U[0], 0.0)
        xtol = 1e-17 * self._t_ref
        for i in range(n_int):
            if U[i + 1] < -tol:
                left = t[i] if U[i] >= 0 else None
                if left is None:
                    return t[i]
                return brentq(u, left, t[i + 1], xtol=xtol, rtol=_RTOL)
            if D[i] < 0 < D[i + 1] and min(U[i], U[i + 1]) - dip < tol:
                tm = brentq(du, t[i], t[i + 1], xtol=xtol, rtol=_RTOL)
                if u(tm) < -tol:
                    return brentq(u, t[i], tm, xtol=xtol, rtol=_RTOL)
        return None

    def integrate(self, z0, t0: float = 0.0, duration: float | None = None, samples_per_period: int = 16,
                  max_events: int = 10_000):
        """Exact motion from z(t₀) = z0 over ``duration`` (default one period).

        Returns
        -------
        segments : list of (phase, t_start, t_end, α)
        z_end : ndarray (2 n_l,)
        Phi : ndarray (2 n_l, 2 n_l)
            d z(t_end) / d z0 (saltation = identity).
        """
        z = np.asarray(z0, dtype=float).copy()
        t_end = t0 + (self.period if duration is None else duration)
        ph = self.phase_of(z)
        t = t0
        segments = []
        Phi = np.eye(2 * self.n_l)
        just = False
        for _ in range(max_events):
            alpha = ph.modal(z, t)
            t_sw = self._first_switch(ph, alpha, t, t_end, samples_per_period, just)
            stop = t_end if t_sw is None else t_sw
            segments.append((ph, t, stop, alpha))
            Phi = ph.transition(stop - t) @ Phi
            z = ph.state(alpha, t, stop)
            if t_sw is None:
                return segments, z, Phi
            t = stop
            ph = self.closed if ph is self.open else self.open
            just = True
        raise RuntimeError(f"more than {max_events} switches in one period")


@dataclass(frozen=True, eq=False)
class ForcedOrbit:
    """A periodic forced response of the exact piecewise-linear system.

    Attributes
    ----------
    frequency : float
        Excitation frequency (Hz).
    z0 : ndarray (2 n_l,)
        (q_l, v_l) at t = 0 (the force's phase reference).
    switch_times : ndarray
        Times (s) in [0, T) of the contact switches.
    n_contacts : int
        Closed phases per period.
    converged : bool
    iterations : int
    residual : float
        max |z(T) − z₀| relative to max |z₀|.
    multipliers : ndarray, complex (2 n_l,)
        Floquet multipliers, by decreasing modulus.
    system : ForcedSystem
    """

    frequency: float
    z0: np.ndarray
    switch_times: np.ndarray
    n_contacts: int
    converged: bool
    iterations: int
    residual: float
    multipliers: np.ndarray
    system: ForcedSystem
    segments: list

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray]:
        """All DOFs q (n_dof, n_t) and the contact force λ (n_t,) at times t in [0, T]."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        n = self.system.n_l
        ql = np.empty((n, t.size))
        for ph, a, b, alpha in self.segments:
            m = (t >= a) & (t <= b)
            if m.any():
                ql[:, m] = ph.state(alpha, a, t[m])[:n]
        return self.system.base.state_to_full(ql)

    def fourier(self, dof: int, harmonics: int, nodes: int = 48) -> np.ndarray:
        """NLvib-ordered Fourier coefficients (2H+1,) of q[dof](τ), τ = Ω t, by Gauss–Legendre
        quadrature on every smooth piece (exact to round-off for smooth pieces)."""
        x, w = np.polynomial.legendre.leggauss(nodes)
        om = self.system.omega
        k = np.arange(1, harmonics + 1)
        out = np.zeros(2 * harmonics + 1)
        for _, a, b, _ in self.segments:
            # split long pieces so that each holds a few oscillations of the fastest harmonic
            n_sub = max(1, math.ceil((b - a) * om * max(harmonics, 1) / np.pi))
            edges = np.linspace(a, b, n_sub + 1)
            for lo_, hi_ in zip(edges[:-1], edges[1:], strict=True):
                t = 0.5 * (hi_ - lo_) * x + 0.5 * (hi_ + lo_)
                q = self.evaluate(t)[0][dof]
                wt = w * 0.5 * (hi_ - lo_) * om  # dτ
                out[0] += (wt * q).sum()
                out[1::2] += np.cos(np.outer(k, om * t)) @ (wt * q)
                out[2::2] += np.sin(np.outer(k, om * t)) @ (wt * q)
        out[0] /= 2 * np.pi
        out[1:] /= np.pi
        return out

    def amplitude(self, dof: int | None = None, n: int = 4096) -> float:
        """Largest |q[dof]| over the period (m), refined around the sampled peak."""
        return orbit_amplitude(self, dof, n)


def orbit_amplitude(orbit, dof: int | None = None, n: int = 4096) -> float:
    """Largest |q[dof]| (m) of a periodic orbit over its period: the largest of n samples,
    refined by a bounded scalar search within a sample spacing around it. ``orbit`` has
    ``evaluate(t)`` (its first output q, (n_dof, len(t))) and ``system`` with ``model``
    and ``period`` (s); ``dof`` defaults to the model's amplitude DOF."""
    from scipy.optimize import minimize_scalar

    dof = orbit.system.model.amplitude_dof if dof is None else dof
    T = orbit.system.period
    t = T * np.arange(n) / n
    q = orbit.evaluate(t)[0][dof]
    j = int(np.argmax(np.abs(q)))
    sign = np.sign(q[j])
    res = minimize_scalar(lambda s: -sign * orbit.evaluate([s % T])[0][dof, 0],
                          bounds=(t[j] - T / n, t[j] + T / n), method="bounded",
                          options={"xatol": 1e-14 * T})
    return float(max(abs(q[j]), -res.fun))


def forced_orbit(model, force, frequency: float, guess=None, *, tol: float = 1e-12, max_iter: int = 40,
                 samples_per_period: int = 16) -> ForcedOrbit:
    """The periodic response of period 1/``frequency`` by Newton shooting.

    Parameters
    ----------
    model : Model
    force : array_like (n_dof,) or Excitation
    frequency : float
        Excitation frequency (Hz).
    guess : ndarray (2 n_l,), optional
        (q_l(0), v_l(0)); default: the linear response (contact ignored).
    tol : float
        On max |z(T) − z₀| / max |z₀|.

    Returns
    -------
    ForcedOrbit
        Check ``converged``.
    """
    omega = 2 * np.pi * check.positive("frequency", frequency)
    system = ForcedSystem(model, force, omega)
    n = system.n_l
    if guess is None:
        ph = system.open
        z = ph.particular(0.0)[0]
    else:
        z = np.asarray(guess, dtype=float).copy()
        if z.shape != (2 * n,):
            raise ValueError(f"guess must have shape ({2 * n},), got {z.shape}")
    converged, res, it = False, np.inf, 0
    for it in range(1, max_iter + 1):  # noqa: B007 - the count is reported
        _, zT, Phi = system.integrate(z, 0.0, None, samples_per_period)
        r = zT - z
        res = float(np.abs(r).max() / max(np.abs(z).max(), 1e-300))
        if res <= tol:
            converged = True
            break
        dz = la.solve(Phi - np.eye(2 * n), -r)
        # damp far from the solution
        scale = max(np.abs(z).max(), 1e-300)
        step = float(np.abs(dz).max())
        if step > scale:
            dz *= scale / step
        z = z + dz
    segments, _, Phi = system.integrate(z, 0.0, None, samples_per_period)
    switches = np.array([a for ph, a, b, _ in segments[1:]])
    mu = la.eigvals(Phi)
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    n_contacts = sum(1 for ph, a, b, _ in segments if ph.name == "closed")
    if segments[0][0].name == "closed" and segments[-1][0].name == "closed" and len(segments) > 1:
        n_contacts -= 1  # one closed phase straddling t = 0
    return ForcedOrbit(omega / (2 * np.pi), z, switches, n_contacts, converged, it, res, mu, system, segments)
