"""Floquet stability of periodic solutions with massless contact nodes.

Because the contact DOFs are massless, the motion of the DOFs with mass is a
*continuous* piecewise-linear flow (docs/exact.md): in a phase with the set A of
contacts closed, the massless DOFs of A are held at their stops and the others follow
statically, so

    M_ll δq'' + C_eff δq' + K_A δq = 0,     K_A = K_ll − K_lf K_ff⁻¹ K_fl   (f = c \\ A),

for a perturbation δq of the DOFs with mass (C_eff = C_ll − ξ M_ll for the damped modes
of the EPMC, C_ll for forced responses, 0 for conservative orbits; the forcing drops
out of the variational equation). The vector field is continuous across a switch
(the contact force and the gap vanish together), so the saltation matrices are the
identity and the monodromy matrix is the ordered product of the phases' matrix
exponentials,

    Φ(T) = Π_s exp(A_s Δt_s),    A_s = [[0, I], [−M⁻¹K_s, −M⁻¹C_eff]].

For a harmonic-balance solution the phases are taken *along the converged orbit*: at
each instant the contact state is the one the exact flow has at the orbit's positions
of the DOFs with mass q_l(τ) (the box-constrained static equilibrium of the massless
DOFs, which depends on q_l alone), and the switching instants are the roots of the
phase's switching functions (a closed contact's force, an open contact's distance to its
stop), trigonometric polynomials of degree H in τ, bracketed on a fine grid and refined
by brentq. (The truncated contact signals themselves are a poor clock: p = q − f/r of a
degree-H solution crosses its bound ~0.07 rad early at H = 7 on the forced oscillator,
where q_l crosses within 1e-3 of the exact instant.) The multipliers are those of the
exact flow linearised about the approximate orbit: their error is of the order of the
orbit's, which converges with H. Known structure (tests): for a conservative orbit every
exp(A_s t) is symplectic, so the multipliers come in reciprocal pairs μ, 1/μ to
round-off; the two trivial multipliers (phase and energy) equal +1 up to the orbit's
error.

:func:`classify` counts multipliers outside the unit circle along a branch and names
where they cross: ``"fold"``/``"branch_point"`` (a real multiplier through +1),
``"period_doubling"`` (through −1), ``"neimark_sacker"`` (a complex pair).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la
from scipy.optimize import brentq

from ..._method_info import METHOD_INFO, method_info
from ...core.special_points import SpecialPoint
from ...model.contact import admissible_intervals
from ...model.model import Model
from .damped import fine_samples

__all__ = ["FloquetSolver", "classify", "conservative_multipliers", "branch_stability"]


class FloquetSolver:
    """Contact phases and monodromy matrices of the piecewise-linear flow of a
    :class:`Model` (dense; meant for up to a few hundred DOFs with mass).

    Parameters
    ----------
    model : Model
        Massless contact DOFs; ``model.damping`` is used (zero without).
    """

    def __init__(self, model: Model):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        b = model.blocks
        self.model = model
        self.M = b["M_ll"].toarray()
        self.K_ll = b["K_ll"].toarray()
        self.K_lc = np.asarray(b["K_lc"])
        self.K_cc = np.asarray(b["K_cc"])
        self.C = b["C_ll"].toarray() if b["C_ll"] is not None else np.zeros_like(self.M)
        self.n_l, self.n_c = self.M.shape[0], self.K_cc.shape[0]
        dofs, self.lo, self.hi = admissible_intervals(model.contacts)
        self.rows = np.searchsorted(model.c, dofs)
        self.Minv = np.linalg.inv(self.M)
        self._K = {}
        self._dec = {}
        self._switch = {}

    # ------------------------------------------------------------------ phases
    def _closed_rows(self, closed) -> dict:
        """{row in c: bound value} of the closed contacts ``closed`` = ((j, ±1), ...)."""
        return {int(self.rows[j]): (self.hi[j] if side > 0 else self.lo[j]) for j, side in closed}

    def stiffness(self, closed: frozenset) -> np.ndarray:
        """K_A of the phase with the contacts ``closed`` ((contact index, ±1 for hi/lo), ...)."""
        K = self._K.get(closed)
        if K is None:
            held = self._closed_rows(closed)
            f = np.array([i for i in range(self.n_c) if i not in held], dtype=int)
            K = self.K_ll.copy()
            if len(f):
                K -= self.K_lc[:, f] @ la.solve(self.K_cc[np.ix_(f, f)], self.K_lc[:, f].T, assume_a="pos")
            K = 0.5 * (K + K.T)
            self._K[closed] = K
        return K

    def switching_functions(self, closed: frozenset) -> tuple[np.ndarray, np.ndarray, list]:
        """Affine functions u = W q_l + w0 that are positive while the phase ``closed`` holds:
        the contact force of each closed contact and the distance to each stop of the
        open ones. Returns W (n_sw, n_l), w0 (n_sw,) and what each row means
        (("force", j, side) or ("gap", j, side))."""
        hit = self._switch.get(closed)
        if hit is not None:
            return hit
        held = self._closed_rows(closed)
        A = np.array(sorted(held), dtype=int)
        f = np.array([i for i in range(self.n_c) if i not in held], dtype=int)
        yA = np.array([held[i] for i in A])
        Kff = self.K_cc[np.ix_(f, f)]
        Yl = -la.solve(Kff, self.K_lc[:, f].T) if len(f) else np.zeros((0, self.n_l))
        Y0 = -la.solve(Kff, self.K_cc[np.ix_(f, A)] @ yA) if len(f) and len(A) else np.zeros(len(f))
        W, w0, what = [], [], []
        for j, side in sorted(closed):
            i = int(self.rows[j])
            a = int(np.searchsorted(A, i))
            # the needed force at row i: K_il q_l + K_iA y_A + K_if y_f; λ = −side · it
            gl = self.K_lc[:, i] + (self.K_cc[i, f] @ Yl if len(f) else 0.0)
            g0 = self.K_cc[i, A] @ yA + (self.K_cc[i, f] @ Y0 if len(f) else 0.0)
            W.append(-side * gl)
            w0.append(-side * g0)
            what.append(("force", j, side))
            del a
        closed_idx = {j for j, _ in closed}
        for j in range(len(self.rows)):
            if j in closed_idx:
                continue
            k = int(np.searchsorted(f, self.rows[j]))
            for side, bound in ((1, self.hi[j]), (-1, self.lo[j])):
                if np.isfinite(bound):
                    W.append(-side * Yl[k])
                    w0.append(side * (bound - Y0[k]))
                    what.append(("gap", j, side))
        out = (np.array(W).reshape(-1, self.n_l), np.array(w0), what)
        self._switch[closed] = out
        return out

    def phase_at(self, q_l: np.ndarray) -> frozenset:
        """The closed contacts at the positions ``q_l`` (n_l,): the box-constrained static
        equilibrium of the massless DOFs, by an active-set iteration."""
        closed = frozenset()
        for _ in range(4 * len(self.rows) + 4):
            W, w0, what = self.switching_functions(closed)
            u = W @ q_l + w0
            if len(u) == 0 or u.min() >= 0:
                return closed
            k = int(np.argmin(u))
            kind, j, side = what[k]
            closed = (closed - {(j, side)}) if kind == "force" else (closed | {(j, side)})
        raise RuntimeError("the contact active set at τ = 0 did not settle")

    def phases(self, Ql: np.ndarray, n_grid: int | None = None) -> list:
        """Phases (τ_start, τ_end, closed) over [0, 2π) of the orbit whose DOFs with mass have
        NLvib-ordered coefficients ``Ql`` (n_l, 2H+1): the contact state the exact flow
        has at those positions, switching instants located by brentq on the trigonometric
        switching functions (first root after the last switch; a grid of ``n_grid`` points,
        default max(512, 32 (2H+1)), brackets it)."""
        Ql = np.asarray(Ql, dtype=float)
        H = (Ql.shape[1] - 1) // 2
        n = n_grid or max(512, 2 ** int(np.ceil(np.log2(32 * (2 * H + 1)))))
        tau = 2 * np.pi * np.arange(n + 1) / n
        harmonics = np.arange(1, H + 1)
        closed = self.phase_at(Ql[:, 0] + Ql[:, 1::2].sum(axis=1))
        t, segments = 0.0, []
        for _ in range(4 * n):
            W, w0, _what = self.switching_functions(closed)
            if len(w0) == 0:
                break
            coef = W @ Ql
            coef[:, 0] += w0
            scale = np.abs(W) @ np.abs(Ql).sum(axis=1) + np.abs(w0) + 1e-300
            i0 = int(np.searchsorted(tau, t, side="right"))
            grid = fine_samples(coef, n)
            vals = np.concatenate([grid, grid[:, :1]], axis=1)[:, i0:]  # (n_sw, n_g), τ = 2π repeats τ = 0
            neg = vals < -1e-12 * scale[:, None]
            first = np.where(neg.any(axis=1), neg.argmax(axis=1), vals.shape[1])
            k = int(np.argmin(first))
            if first[k] == vals.shape[1]:
                break
            g = i0 + int(first[k])
            c = coef[k]

            def fun(s, c=c):  # the switching function's series at s
                return float(c[0] + c[1::2] @ np.cos(harmonics * s) + c[2::2] @ np.sin(harmonics * s))

            left = tau[g - 1] if g - 1 >= i0 else t
            left = max(left, t)
            if fun(left) < 0:  # just switched: the root sits at t within round-off
                left = t
            if fun(left) > 0:
                t_sw = brentq(fun, left, tau[g], xtol=1e-15, rtol=4 * np.finfo(float).eps)
            else:
                t_sw = left
            if t_sw > t:
                segments.append((t, t_sw, closed))
            kind, j, side = _what[k]
            closed = (closed - {(j, side)}) if kind == "force" else (closed | {(j, side)})
            t = t_sw
        segments.append((t, 2 * np.pi, closed))
        return [s for s in segments if s[1] > s[0]]

    # ------------------------------------------------------------------ monodromy
    def transition(self, closed: frozenset, duration: float, xi: float = 0.0,
                   damping: bool = True) -> np.ndarray:
        """exp(A duration) of the phase ``closed``, shape (2 n_l, 2 n_l), from an
        eigendecomposition cached per (phase, ξ): without damping the real modes of
        (K_A, M) (a symplectic matrix to round-off), else the complex eigenpairs of A."""
        conservative = (not damping or not np.any(self.C)) and xi == 0.0
        key = (closed, xi, damping)
        dec = self._dec.get(key)
        if dec is None:
            K = self.stiffness(closed)
            if conservative:
                lam, Phi = la.eigh(K, self.M)
                dec = ("real", np.sqrt(np.maximum(lam, 0.0)), Phi, Phi.T @ self.M)
            else:
                n = self.n_l
                C = (self.C if damping else 0.0) - xi * self.M
                A = np.zeros((2 * n, 2 * n))
                A[:n, n:] = np.eye(n)
                A[n:, :n] = -self.Minv @ K
                A[n:, n:] = -self.Minv @ C
                dec = ("complex",) + _real_eigenbasis(A)
            if len(self._dec) > 64:
                self._dec.clear()
            self._dec[key] = dec
        kind, lam, V, W = dec
        if kind == "real":
            w = lam
            c, s = np.cos(w * duration), np.sin(w * duration)
            with np.errstate(invalid="ignore", divide="ignore"):
                sinc = np.where(w > 0, s / np.where(w > 0, w, 1.0), duration)
            qq = (V * c) @ W
            return np.block([[qq, (V * sinc) @ W], [(V * (-w * s)) @ W, qq]])
        # real Jordan form: a pair σ ± iω with eigenvectors a ± ib spans columns (a, b)
        sigma, omega_i = lam.real, lam.imag
        e = np.exp(sigma * duration)
        c, s = e * np.cos(omega_i * duration), e * np.sin(np.abs(omega_i) * duration)
        pair = omega_i != 0.0
        VE = V * c
        partner = np.arange(len(lam)) + np.where(omega_i > 0, 1, -1)
        partner[~pair] = np.arange(len(lam))[~pair]
        VE[:, pair] -= V[:, partner[pair]] * (np.sign(omega_i[pair]) * s[pair])
        return VE @ W

    def monodromy(self, segments, omega: float, xi: float = 0.0, damping: bool = True) -> np.ndarray:
        """Φ(T), shape (2 n_l, 2 n_l), of the state (δq_l, δv_l) over the phases
        (τ_start, τ_end, closed) at frequency Ω (rad/s); C_eff = C − ξM (−ξM without
        ``damping``)."""
        Phi = np.eye(2 * self.n_l)
        for a, b, closed in segments:
            Phi = self.transition(closed, (b - a) / omega, xi, damping) @ Phi
        return Phi

    def multipliers(self, Ql: np.ndarray, omega: float, xi: float = 0.0, damping: bool = True) -> np.ndarray:
        """Floquet multipliers (2 n_l,) of the orbit with coefficients ``Ql`` (n_l, 2H+1) of
        the DOFs with mass at Ω (rad/s), sorted by decreasing modulus."""
        mu = la.eigvals(self.monodromy(self.phases(Ql), omega, xi, damping))
        return mu[np.argsort(-np.abs(mu), kind="stable")]


def _real_eigenbasis(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(λ, V_r, V_r⁻¹) of a real matrix with V_r real: for each complex pair σ ± iω
    (eigenvectors a ± ib) the columns (a, b) with λ = (σ + iω, σ − iω) in that order, so
    that exp(A t) = V_r E(t) V_r⁻¹ with 2×2 blocks e^{σt} [[cos ωt, sin ωt], [−sin ωt, cos ωt]]
    acting on (a, b) — all in real arithmetic (complex products of this size are slow)."""
    lam, V = la.eig(A)
    n = len(lam)
    order = []
    used = np.zeros(n, dtype=bool)
    for i in np.argsort(-lam.imag, kind="stable"):
        if used[i] or lam[i].imag < 0:
            continue
        used[i] = True
        if lam[i].imag == 0:
            order.append((i, None))
            continue
        j = int(np.argmin(np.abs(lam - np.conj(lam[i])) + used * 1e300))
        used[j] = True
        order.append((i, j))
    for i in np.flatnonzero(~used):  # unmatched (should not happen for a real matrix)
        order.append((int(i), None))
    lam_r = np.empty(n, dtype=complex)
    Vr = np.empty((n, n))
    k = 0
    for i, j in order:
        if j is None:
            lam_r[k] = lam[i].real
            Vr[:, k] = V[:, i].real if np.any(V[:, i].real) else V[:, i].imag
            k += 1
        else:
            lam_r[k], lam_r[k + 1] = lam[i], np.conj(lam[i])
            Vr[:, k], Vr[:, k + 1] = V[:, i].real, V[:, i].imag
            k += 2
    return lam_r, Vr, la.inv(Vr)


def conservative_multipliers(problem, u: np.ndarray) -> np.ndarray:
    """Floquet multipliers of a point ``u`` of the conservative MMS-HBM
    (:class:`~mmshbm.methods.mms.conservative.MMSHBMProblem`), sorted by decreasing modulus; the
    model's damping is ignored (the orbit is that of the undamped structure)."""
    _, omega = problem.unpack(u)
    Q = problem.coefficients(u)
    solver = problem._floquet_solver
    if solver is None:
        solver = FloquetSolver(problem.model)
        problem._floquet_solver = solver
    return solver.multipliers(Q[problem.model.l], omega, 0.0, damping=False)


def _drop_trivial(mu: np.ndarray, n: int) -> tuple[np.ndarray, float]:
    """The multipliers without the ``n`` closest to +1, and the largest distance of those from 1."""
    if n == 0:
        return mu, 0.0
    order = np.argsort(np.abs(mu - 1.0), kind="stable")
    return np.delete(mu, order[:n]), float(np.max(np.abs(mu[order[:n]] - 1.0)))


def classify(multipliers: np.ndarray, trivial: int = 0, tol: float = 1e-6,
             folds=()) -> tuple[np.ndarray, list]:
    """Stability and bifurcations along a branch from its Floquet multipliers.

    Parameters
    ----------
    multipliers : ndarray, complex, shape (n_points, m)
    trivial : int
        Multipliers at +1 by construction: 0 forced, 1 damped modes (phase), 2 conservative
        orbits (phase and energy); the ``trivial`` ones closest to +1 are left out.
    tol : float
        A multiplier is outside the unit circle when |μ| > 1 + tol + 10 × (the trivial
        ones' distance from 1, a measure of the orbit's own error).
    folds : iterable of int
        Indices of the continuation's folds: a real multiplier through +1 within one
        point of a fold is that fold, not a branch point.

    Returns
    -------
    stable : ndarray of bool, shape (n_points,)
    special : list of SpecialPoint
        Where the number of multipliers outside the unit circle changes between two
        points, at the later one: ``"branch_point"`` (the crossing multiplier real and
        > 0), ``"period_doubling"`` (real < 0), ``"neimark_sacker"`` (a complex pair),
        with ``data["multiplier"]`` = [Re, Im] of the crossing multiplier (the one
        nearest the unit circle on the side with more multipliers outside) and
        ``data["unstable"]`` the new count outside.
    """
    mu_all = np.asarray(multipliers)
    n_pts = mu_all.shape[0]
    stable = np.ones(n_pts, dtype=bool)
    outside = [np.empty(0, dtype=complex)] * n_pts
    for i in range(n_pts):
        mu, err = _drop_trivial(mu_all[i][np.isfinite(mu_all[i])], trivial)
        out = mu[np.abs(mu) > 1.0 + tol + 10 * err]
        outside[i] = out
        stable[i] = out.size == 0
    folds = {int(f) for f in folds}
    special = []
    for i in range(1, n_pts):
        a, b = outside[i - 1], outside[i]
        if a.size == b.size:
            continue
        more = b if b.size > a.size else a
        m = more[np.argmin(np.abs(more))]
        real = abs(m.imag) <= 1e-7 * max(1.0, abs(m))
        kind = ("branch_point" if m.real > 0 else "period_doubling") if real else "neimark_sacker"
        if kind == "branch_point" and folds & {i - 1, i, i + 1}:
            continue  # the continuation's fold is this crossing
        special.append(SpecialPoint(kind, i, multiplier=[float(m.real), float(m.imag)], unstable=int(b.size)))
    return stable, special


def branch_stability(branch, tol: float = 1e-6):
    """Floquet multipliers, stability and bifurcations of every point of a backbone
    (:class:`~mmshbm.results.branch.Branch` of method "mmshbm" (conservative: two trivial
    multipliers) or "epmc" (damped mode, flow with C − ξM: one trivial multiplier)).

    Returns
    -------
    multipliers : ndarray, complex, shape (n_points, 2 n_l)
    stable : ndarray of bool, shape (n_points,)
    special : list of SpecialPoint
        As :func:`classify`.
    """
    trivial = method_info(branch.method).floquet_trivial
    if trivial not in (1, 2):
        able = sorted(m for m, info in METHOD_INFO.items() if info.floquet_trivial)
        raise ValueError(f"branch_stability handles backbones of the methods {able}, got {branch.method!r}")
    solver = branch._require_solver()
    if trivial == 1:  # a damped mode's flow
        mu = np.array([solver.floquet_multipliers(u) for u in branch.states])
    else:  # a conservative flow
        mu = np.array([conservative_multipliers(solver, u) for u in branch.states])
    folds = [p.index for p in branch.special_points if p.kind == "fold"]
    stable, special = classify(mu, trivial=trivial, tol=tol, folds=folds)
    return mu, stable, special
