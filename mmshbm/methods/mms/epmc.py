"""Damped nonlinear modes by MMS-HBM: the extended periodic motion concept (EPMC).

Krack (2015) defines the nonlinear mode of a damped structure as the periodic solution
of the *autonomous* system with an artificial negative mass-proportional damping −ξM
that compensates the dissipation,

    M q'' + (C − ξ M) q' + K q = Σ w_i λ_i,       Signorini at every stop,

with ξ (1/s) an unknown along with the motion and Ω. The modal damping ratio of the
nonlinear mode is D = ξ/(2Ω); for a linear structure with modal damping ζ_j it gives
Ω = ω_j and D = ζ_j exactly (the mode's damping 2ζ_jω_j − ξ vanishes), and with C = 0
it gives ξ = 0 and the conservative backbone (tests check both).

Here the massless DOFs carry the full cosine and sine series (the damped mode is not
time-symmetric), the linear structure is condensed per harmonic with
S_k = K_ll + ikΩ(C_ll − ξM_ll) − (kΩ)²M_ll (:mod:`mmshbm.methods.mms.condensation.damped_condense`), and the
contact residual is that of :mod:`mmshbm.methods.mms.damped`. Unknowns
u = [x, ξ, Ω] (scaled): n_c(2H+1) + 2 numbers. Equations: the n_c(2H+1) projected
residuals and a *phase anchor*, the sine coefficient of the anchor DOF's fundamental set
to zero (the amplitude DOF, or the first contact DOF when that one carries mass), since
a time shift of a solution is a solution. The amplitude is not normalised: the
coefficients are physical, so the family is a curve in (x, ξ, Ω) that pseudo-arclength
continuation follows from the linear mode; ξ takes the rank the conservative family's
energy identity removes, so the bordered Jacobian stays regular at C = 0.

Ω is the last unknown (the continuation's folds are folds in frequency, as for
backbones).

The family guard of :mod:`mmshbm.family.guard` keeps the branch on the starting mode's
family as for conservative backbones: every point records ``fundamental_share``, the
fundamental harmonic's share of the period-mean kinetic energy. Where a harmonic k meets
a damped higher mode j (kΩ ≈ ω_j) the energy moves into mode j, the damping ratio of
the nonlinear mode rises with it and the path can close into a loop (on the 21-element
beam at H = 20, harmonics 4 and 5 near the second mode fold the branch at 3.8 gaps,
66 Hz, back down to 2 gaps and around); the guard sees the branch come back onto the
family below its frontier and jumps past the loop by solves at a pinned amplitude
(:meth:`scaled_state`, :meth:`family_frequency_limit`).
"""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...core.measures import check_dof, harmonic_content, mean_energy, refined_argmax
from ...core.problem import BackboneProblemBase, OneEvaluation
from ...model.model import Model
from .damped import DampedHBMBase, fine_samples, synthesis_matrix
from .held import _held_frequency

__all__ = ["EPMCProblem", "fundamental_share"]


def fundamental_share(M, Q: np.ndarray) -> float:
    """Share (0..1) of the period-mean kinetic energy in the fundamental harmonic of the
    motion with NLvib-ordered coefficients ``Q`` (n_dof, 2H+1) and mass matrix ``M``
    (n_dof, n_dof): T_k ∝ k²(Q_ckᵀMQ_ck + Q_skᵀMQ_sk). 1 for a motion at rest."""
    MQ = np.einsum("ij,ij->j", Q, M @ Q)
    k = np.arange(1, (Q.shape[1] - 1) // 2 + 1)
    T = k**2 * (MQ[1::2] + MQ[2::2])
    total = float(T.sum())
    return float(T[0] / total) if total > 0 else 1.0


class _Landed(Exception):
    """Ends the path following of :meth:`EPMCProblem.family_landing` (u None: a loop)."""

    def __init__(self, u, amplitude: float):
        super().__init__()
        self.u, self.amplitude = u, amplitude


class EPMCProblem(OneEvaluation, DampedHBMBase, BackboneProblemBase):
    """Damped nonlinear mode (EPMC) by MMS-HBM, as a continuation problem.

    Parameters
    ----------
    model : Model
        Massless contact DOFs; damping optional (zero damping gives the conservative mode).
    harmonics : int
        H >= 1.
    n_samples, r, backend, projection
        As in :class:`~mmshbm.methods.mms.damped.DampedHBMBase`.
    mode : int
        The linear mode (1-based) the branch starts from.

    Notes
    -----
    Scaled unknowns ``u = [x / xscale, ξ / ω_ref, Ω / ω_ref]``. Monitored per point:
    frequency (Hz), amplitude (m: for a single contact the contact DOF's largest
    excursion away from the stop, as for backbones; else the largest |q| of
    ``model.amplitude_dof``), energy (J), contact_force_max (N), damping_ratio
    (ξ/(2Ω)), xi (1/s).
    """

    method = "epmc"
    #: (key, landing or None) of the last :meth:`family_landing`, for the jump's repeated calls
    _landing_memo: tuple | None = None
    #: the Floquet solver of the multipliers; None until built
    _floquet = None

    def __init__(self, model: Model, harmonics: int = 5, n_samples: int | None = None, r: float | None = None,
                 mode: int = 1, backend: str = "auto", projection: str = "exact"):
        super().__init__(model, harmonics, n_samples, r, backend, "MMS-HBM (EPMC)", projection=projection)
        self.mode = check.integer("mode", mode, minimum=1)
        if self.mode > self.cond.n_l:
            raise ValueError(f"mode must be <= the number of DOFs with mass ({self.cond.n_l}), "
                             f"got {self.mode}")
        freqs, modes = model.linear_modes(self.mode)
        phi = modes[:, -1]
        c = model.c
        try:
            amp_dof = model.amplitude_dof
        except ValueError:
            amp_dof = model.contacts[0].dof
        i_amp = int(np.searchsorted(c, amp_dof))
        self.anchor = i_amp if i_amp < len(c) and c[i_amp] == amp_dof else int(self.contact_rows[0])
        ref = abs(phi[amp_dof])
        if not ref > 1e-12 * np.max(np.abs(phi)):
            raise ValueError(f"linear mode {self.mode} does not move the amplitude DOF {amp_dof}")
        self.mode_shape = phi[c] / ref
        self.mode_frequency = float(freqs[-1])
        C = model.damping
        self.mode_xi = float(phi @ (C @ phi)) if C is not None else 0.0  # 2 ζ ω for a mass-normalised mode
        self.amplitude_dof = amp_dof
        self._anchor_col = 2 * self.n_c + self.anchor  # the sine of harmonic 1 is block 2
        self.colscale = np.concatenate([self.xscale, [self.omega_ref, self.omega_ref]])
        self.n_unknowns = self.n_x + 2
        # columns of u holding the amplitude DOF's coefficients (None: a DOF with mass)
        self._amp_col = (np.arange(self.n_coef) * self.n_c + int(np.searchsorted(c, amp_dof))
                         if i_amp < len(c) and c[i_amp] == amp_dof else None)

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float, float]:
        """Scaled unknowns -> (x (n_x,) m/rad, ξ (1/s), Ω (rad/s))."""
        if np.shape(u) != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {np.shape(u)}")
        y = np.asarray(u, dtype=float) * self.colscale
        return y[:-2], float(y[-2]), float(y[-1])

    def pack(self, x: np.ndarray, xi: float, omega: float) -> np.ndarray:
        return np.concatenate([np.asarray(x, dtype=float), [xi, omega]]) / self.colscale

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        """Scaled unknowns of the linear mode with amplitude ``amplitude`` (m) at the
        amplitude DOF (cosine, toward the stop at τ = 0), ξ = φᵀCφ, Ω = ω_mode."""
        amplitude = check.positive("amplitude", amplitude)
        x = np.zeros(self.n_x)
        x[self.n_c:2 * self.n_c] = amplitude * self.mode_shape
        return self.pack(x, self.mode_xi, 2 * np.pi * self.mode_frequency)

    def initial_tangent(self) -> np.ndarray:
        """Growing amplitude at constant ξ and Ω."""
        t = self.linear_mode_point(1.0)
        t[-2:] = 0.0
        return t / np.linalg.norm(t)

    # ------------------------------------------------------------------ residual

    def _evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual (n_x + 1,) and, if asked, its Jacobian (n_x + 1, n_x + 2)."""
        x, xi, omega = self.unpack(u)
        ch = self._condensed(omega, xi, jacobian, jacobian)
        R = np.empty(self.n_x + 1)
        R[-1] = u[self._anchor_col]
        if not jacobian:
            R[:-1] = self.fused_residual(ch.D, x, None)[0] / self.rowscale
            return R
        Rx, Jx, Jp = self.fused_residual(ch.D, x, None, np.stack([ch.dD_dxi, ch.dD_domega]))
        R[:-1] = Rx / self.rowscale
        J = np.zeros((self.n_x + 1, self.n_x + 2))
        J[:-1, :-2] = Jx * self.xscale[None, :]
        J[:-1, -2:] = Jp * self.omega_ref
        J[:-1] /= self.rowscale[:, None]
        J[-1, self._anchor_col] = 1.0
        return R, J

    # ------------------------------------------------------------------ results
    def coefficients(self, u: np.ndarray) -> np.ndarray:
        """NLvib-ordered coefficients of all DOFs, shape (n_dof, 2H+1)."""
        x, xi, omega = self.unpack(u)
        return self.full_coefficients(x, self._condensed(omega, xi, recover=True), None)

    def angular_frequency(self, u: np.ndarray) -> float:
        """Ω (rad/s) of the scaled unknowns ``u``."""
        return self.unpack(u)[2]

    def contact_force(self, u: np.ndarray, n_samples: int = 256):
        """(t (n_samples,) s, λ (n_samples,) N) of the first contact (all contacts: rows of
        a (n_contacts, n_samples) array when there are several)."""
        x, xi, omega = self.unpack(u)
        F = self.needed_force(x, self._condensed(omega, xi).D, None)
        n_samples = check.integer("n_samples", n_samples, minimum=1)
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        E = synthesis_matrix(self.H, tau)
        c = self.model.c
        lam = np.array([-ct.side * (E @ F[self._coef_index[int(np.searchsorted(c, ct.dof))]])
                        for ct in self.model.contacts])
        return tau / omega, (lam[0] if len(lam) == 1 else lam)

    def harmonic_content(self, u: np.ndarray, dof: int | None = None) -> np.ndarray:
        """|Q̂_k|, k = 0..H, of ``dof`` (default the amplitude DOF); shape (H+1,)."""
        dof = check_dof(dof, self.model.n_dof, self.amplitude_dof)
        return harmonic_content(self.coefficients(u)[dof])

    def monitor(self, u: np.ndarray) -> dict:
        """frequency (Hz), amplitude (m), energy (J), contact_force_max (N),
        damping_ratio (ξ/(2Ω)), xi (1/s)."""
        x, xi, omega = self.unpack(u)
        ch = self._condensed(omega, xi, recover=True)
        Q = self.full_coefficients(x, ch, None)
        F = self.needed_force(x, ch.D, None)
        return {"frequency": omega / (2 * np.pi), "amplitude": self.amplitude(Q[self.amplitude_dof]),
                "energy": mean_energy(self.model, Q, omega),
                "contact_force_max": self.contact_force_max(x, F),
                "damping_ratio": xi / (2 * omega), "xi": xi,
                "fundamental_share": fundamental_share(self.model.M, Q)}

    # ------------------------------------------------------------------ family guard
    def frequency_of(self, u: np.ndarray) -> float:
        """Ω/2π (Hz) of the scaled unknowns ``u`` (no evaluation)."""
        return float(u[-1] * self.colscale[-1] / (2 * np.pi))

    def scaled_state(self, u: np.ndarray, factor: float) -> np.ndarray:
        """``u`` with every displacement coefficient times ``factor``, ξ and Ω kept (far
        above the gap a piecewise-linear system is nearly homogeneous): a predictor of
        the family at ``factor`` times the amplitude of ``u``."""
        out = np.array(u, dtype=float)
        out[:-2] *= factor
        return out

    def amplitude_value(self, u: np.ndarray) -> float:
        """The monitored amplitude (m) of ``u`` alone."""
        if self._amp_col is not None:
            return self.amplitude(u[self._amp_col] * self.colscale[self._amp_col])
        return self.amplitude(self.coefficients(u)[self.amplitude_dof])

    def amplitude_and_gradient(self, u: np.ndarray, h: float = 1e-7) -> tuple[float, np.ndarray]:
        """The monitored amplitude (m) and its gradient with respect to the scaled unknowns
        (the pinned solves of the family guard's jumps). For an amplitude DOF without mass
        the amplitude is the largest value of s·q(τ) with q linear in x: its gradient is
        s·E(τ*) at the maximiser τ* (envelope theorem; τ* from the parabola through the
        fine samples' peak, as the value); otherwise central differences of
        :meth:`amplitude_value`."""
        if self._amp_col is None:
            value = self.amplitude_value(u)
            grad = np.empty(len(u))
            for i in range(len(u)):
                e = np.zeros(len(u))
                e[i] = h
                grad[i] = (self.amplitude_value(u + e) - self.amplitude_value(u - e)) / (2 * h)
            return value, grad
        cols = self._amp_col
        q = u[cols] * self.colscale[cols]
        y = fine_samples(q, self._n_fine)
        contacts = self.model.contacts
        if len(contacts) == 1 and self.model.amplitude_dof == contacts[0].dof and self._away_convention:
            signs = (-contacts[0].side,)
        else:
            signs = (1.0, -1.0)
        best, tau, sign = -np.inf, 0.0, 1.0
        n = len(y)
        for sg in signs:
            value, position = refined_argmax(sg * y)
            if value > best:
                best, tau, sign = value, 2 * np.pi * position / n, sg
        grad = np.zeros(len(u))
        grad[cols] = sign * synthesis_matrix(self.H, np.array([tau]))[0] * self.colscale[cols]
        return best, grad

    def family_landing(self, u_from: np.ndarray, rec_from: dict, excursion: list, amplitude_max: float,
                       amplitude_min: float = 0.0, *, family_share: float):
        """Land on the family beyond an excursion by following the path on: from the
        excursion's last states (``excursion``, scaled unknowns, in order), plain path
        following until a point on the family (fundamental share >= ``family_share``) lies above
        ``amplitude_min`` (the frontier, m). Returns (u, amplitude) of that point for the
        search's pinned solve (:func:`mmshbm.family.deflation.search_beyond`). A damped mode often passes
        a tongue by itself once the branch comes back up; where the path instead closes
        into a loop (it comes back to the excursion's first state) or does not come back
        within twice the excursion's length, raises ValueError and the jump goes on with
        its predictors (``u_from``, ``rec_from``: the origin, unused here)."""
        from ...core.continuation import ContinuationOptions, continue_branch

        if len(excursion) < 2:
            raise ValueError("no excursion to follow")
        memo = self._landing_memo
        key = (len(excursion), np.asarray(excursion[-1], dtype=float).tobytes(), float(amplitude_min))
        if memo is not None and memo[0] == key:
            if memo[1] is None:
                raise ValueError("the path does not come back onto the family above the frontier")
            return memo[1][0].copy(), memo[1][1]
        first = np.asarray(excursion[0], dtype=float)
        steps = np.linalg.norm(np.diff(np.asarray(excursion, dtype=float), axis=0), axis=1)
        closed = 0.5 * float(np.median(steps))
        t0 = np.asarray(excursion[-1], dtype=float) - np.asarray(excursion[-2], dtype=float)
        count = [0]

        def watch(u, rec):
            count[0] += 1
            share = rec.get("fundamental_share", 1.0)
            if share >= family_share and rec["amplitude"] > amplitude_min * (1 + 1e-3):
                raise _Landed(np.array(u, dtype=float), float(rec["amplitude"]))
            if count[0] > 3 and np.linalg.norm(u - first) < closed:
                raise _Landed(None, 0.0)  # the loop closed

        found = None
        try:
            continue_branch(self, np.asarray(excursion[-1], dtype=float), t0 / np.linalg.norm(t0),
                            ContinuationOptions(follow="path", bounds={"amplitude": (0.0, amplitude_max)},
                                                max_steps=min(2 * len(excursion) + 40, 400)),
                            callback=watch, catch_interrupt=False)
        except _Landed as landed:
            found = None if landed.u is None else (landed.u, landed.amplitude)
        self._landing_memo = (key, found)
        if found is None:
            raise ValueError("the path does not come back onto the family above the frontier")
        return found[0].copy(), found[1]

    def family_frequency_limit(self) -> float:
        """The highest frequency (Hz) of the starting mode's family: the linear mode's
        frequency with every contact DOF held at its stop (rigid stops stiffen the
        structure at most that far)."""
        top = _held_frequency(self.model, [ct.dof for ct in self.model.contacts], self.mode)
        return float(max(top, self.mode_frequency))

    def floquet_multipliers(self, u: np.ndarray) -> np.ndarray:
        """Floquet multipliers of the EPMC orbit (the flow with C − ξM; one trivial +1),
        sorted by decreasing modulus (:mod:`mmshbm.methods.mms.stability`)."""
        from .stability import FloquetSolver

        if self._floquet is None:
            self._floquet = FloquetSolver(self.model)
        _, xi, omega = self.unpack(u)
        return self._floquet.multipliers(self.coefficients(u)[self.model.l], omega, xi)
