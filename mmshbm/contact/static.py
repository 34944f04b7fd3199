"""Admissible time signals: the massless DOFs from the exact static contact problem.

A harmonic-balance point gives truncated Fourier series for every DOF. For the massless
DOFs (``model.c``) these series are only approximate: with few harmonics the contact
DOF's series passes through the stop and the contact force's series pulls. The method's
"mixed" idea gives the remedy: the massless DOFs have no inertia, so at every instant
they follow *statically* from the DOFs with mass. Given q_l(t) from the Fourier series,

    K_cc q_c + K_cl q_l = W λ,     g = gap + Wᵀ q_c ≥ 0,   λ ≥ 0,   gᵀλ = 0,

with one column w_j of W per contact (−side_j at the contact's DOF, zero elsewhere; g_j
is the distance of contact j to its stop). Eliminating q_c = B q_l + E λ
(B = −K_cc⁻¹ K_cl, E = K_cc⁻¹ W) gives a linear complementarity problem per instant,

    g = h + G λ,   h = gap + Wᵀ B q_l (the free gaps),   G = Wᵀ K_cc⁻¹ W,

whose solution for a single contact is λ = k_c max(0, −h), k_c = 1/G (``docs/exact.md``).
With several contacts it is solved exactly per sample by enumerating active sets (G is
positive semidefinite and small; the active set of the free gaps is tried first). The
signals are exactly admissible: no penetration, λ ≥ 0, λ = 0 exactly where a contact is
open. They are what the method's solution implies for the massless DOFs, not a new
solution: the DOFs with mass keep their truncated series.

Shooting's signals are already of this kind (its massless DOFs follow from the same
static problem at every step), so :func:`branch_signals` returns them unchanged.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la

from ..model.model import Model
from .lcp import lcp_enumerated

__all__ = ["StaticContact", "admissible_signals", "branch_signals"]

#: largest number of contacts whose LCP is solved by enumerating active sets
MAX_ENUMERATED_CONTACTS = 12


class StaticContact:
    """The static contact problem of the massless DOFs of ``model``.

    Attributes
    ----------
    B : ndarray, shape (n_c, n_l)
        q_c = B q_l + E λ.
    E : ndarray, shape (n_c, n_contacts)
    G : ndarray, shape (n_contacts, n_contacts)
        Wᵀ K_cc⁻¹ W, compliance of the contacts (m/N).
    gaps : ndarray, shape (n_contacts,)
    """

    def __init__(self, model: Model):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        model.require_massless_contacts("admissible signals")
        self.model = model
        b = model.blocks
        c = model.c
        index = {int(d): i for i, d in enumerate(c)}
        W = np.zeros((len(c), model.n_contacts))
        for j, contact in enumerate(model.contacts):
            W[index[int(contact.dof)], j] = -contact.side
        self.W = W
        factor = la.cho_factor(b["K_cc"])
        self.B = -la.cho_solve(factor, b["K_lc"].T)
        self.E = la.cho_solve(factor, W)
        self.G = W.T @ self.E
        self.gaps = np.array([c_.gap for c_ in model.contacts], dtype=float)
        if model.n_contacts > MAX_ENUMERATED_CONTACTS:
            raise ValueError(f"admissible signals enumerate active sets for up to {MAX_ENUMERATED_CONTACTS} "
                             f"contacts; the model has {model.n_contacts}")

    def solve(self, q_l: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Massless DOFs and contact forces for the DOFs with mass ``q_l``.

        Parameters
        ----------
        q_l : ndarray, shape (n_l, n_samples)
            Positions of the DOFs with mass (``model.l`` order).

        Returns
        -------
        q_c : ndarray, shape (n_c, n_samples)
        lam : ndarray, shape (n_contacts, n_samples)
            Contact forces (N), >= 0, exactly 0 where a contact is open.
        """
        q_free = self.B @ q_l
        h = self.gaps[:, None] + self.W.T @ q_free
        if len(self.gaps) == 1:
            lam = np.maximum(0.0, -h) / self.G[0, 0]
        else:
            lam = np.column_stack([self._lcp(h[:, i]) for i in range(h.shape[1])])
        return q_free + self.E @ lam, lam

    def _lcp(self, h: np.ndarray) -> np.ndarray:
        """λ >= 0 with g = h + Gλ >= 0 and g·λ = 0 (exact, by active sets)."""
        return lcp_enumerated(self.G, h)


def admissible_signals(model: Model, Q: np.ndarray, omega: float, n_samples: int = 256,
                       static: StaticContact | None = None):
    """Time signals of a harmonic-balance point with exactly admissible massless DOFs.

    Parameters
    ----------
    model : Model
    Q : ndarray, shape (n_dof, 2H+1)
        NLvib-ordered Fourier coefficients of all DOFs [Q_0, Q_c1, Q_s1, ...] (m, rad);
        only the rows of the DOFs with mass are used.
    omega : float
        Fundamental frequency Ω (rad/s).
    n_samples : int
        Samples per period.
    static : StaticContact, optional
        Reused between calls on one model.

    Returns
    -------
    t : ndarray, shape (n_samples,)
        Time (s) over one period.
    q : ndarray, shape (n_dof, n_samples)
        DOFs with mass: their truncated series; massless DOFs: the static solution.
    lam : ndarray, shape (n_contacts, n_samples)
        Contact forces (N) >= 0.
    """
    if isinstance(n_samples, bool) or not isinstance(n_samples, int | np.integer) or n_samples < 1:
        raise ValueError(f"n_samples must be an integer >= 1, got {n_samples!r}")
    Q = np.asarray(Q, dtype=float)
    if Q.ndim != 2 or Q.shape[0] != model.n_dof or Q.shape[1] % 2 != 1:
        raise ValueError(f"Q must have shape (n_dof={model.n_dof}, 2H+1), got {Q.shape}")
    static = StaticContact(model) if static is None else static
    H = (Q.shape[1] - 1) // 2
    tau = 2 * np.pi * np.arange(n_samples) / n_samples
    k = np.arange(1, H + 1)
    Ql = Q[model.l]
    q_l = Ql[:, :1] + Ql[:, 1::2] @ np.cos(np.outer(k, tau)) + Ql[:, 2::2] @ np.sin(np.outer(k, tau))
    q_c, lam = static.solve(q_l)
    q = np.empty((model.n_dof, n_samples))
    q[model.l] = q_l
    q[model.c] = q_c
    return tau / omega, q, lam


def branch_signals(solver, u: np.ndarray, n_samples: int = 256):
    """(t, q (n_dof, n_samples), λ (n_contacts, n_samples)) with admissible massless DOFs
    at the solver's point ``u``: from ``solver.coefficients(u)`` for harmonic balance;
    shooting's own signals (already admissible) otherwise."""
    model = solver.model
    if not hasattr(solver, "coefficients"):
        t, q = solver.time_signals(u, None, n_samples)
        _, lam = solver.contact_force(u, n_samples)
        return t, q, np.atleast_2d(lam)
    static = getattr(solver, "_static_contact", None)
    if static is None:
        static = StaticContact(model)
        try:
            solver._static_contact = static
        except AttributeError:  # pragma: no cover - a solver with __slots__
            pass
    _, omega = solver.unpack(u)
    return admissible_signals(model, solver.coefficients(u), omega, n_samples, static)
