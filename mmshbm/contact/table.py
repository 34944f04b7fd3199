"""Contact data the methods and the exact reference share: the contacts of a model as
arrays, the static stiffness at each contact, the penalty values, the contacts in terms of
the DOFs with mass (the LCP data) and the start mode.

A model's contacts (:class:`~mmshbm.model.contact.Contact`) put rigid stops at
``q[dof_i] = side_i gap_i``; the gap of contact i is ``g_i = gap_i − side_i q[dof_i]`` and
its force λ_i >= 0 acts on the structure as ``w_i λ_i`` with ``w_i = −side_i e_dof_i``.

The amplitude convention and its peak measure are :mod:`mmshbm.core.measures`
(``amplitude_sign`` and ``refined_peak`` here are its objects, at the names of earlier
releases).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..core.measures import amplitude_peak as refined_peak
from ..core.measures import amplitude_sign
from ..model.model import Model

__all__ = ["DEFAULT_PENALTY_FACTOR", "ContactTable", "contact_table", "static_contact_stiffness",
           "penalty_values", "contact_law", "start_mode", "amplitude_sign", "refined_peak"]

#: Default penalty stiffness in units of the static stiffness at the contact k_c.
DEFAULT_PENALTY_FACTOR = 1e3

# Two linear frequencies closer than this (relative) span one eigenspace (a degenerate mode).
_DEGENERATE_REL = 1e-8


@dataclass(frozen=True)
class ContactTable:
    """The contacts of a model as arrays.

    Attributes
    ----------
    dof, side : ndarray of int, shape (n_ct,)
        DOF and stop side (±1) of each contact.
    gap : ndarray, shape (n_ct,)
        Gap of each contact (m).
    dofs : ndarray of int, shape (n_d,)
        The distinct contact DOFs in order of first appearance (a clearance's DOF once).
    slot : ndarray of int, shape (n_ct,)
        Position of each contact's DOF in ``dofs``.
    massless : ndarray of bool, shape (n_ct,)
        Whether each contact's DOF is massless.
    """

    dof: np.ndarray
    side: np.ndarray
    gap: np.ndarray
    dofs: np.ndarray
    slot: np.ndarray
    massless: np.ndarray

    @property
    def n(self) -> int:
        """Number of contacts."""
        return len(self.dof)


def contact_table(model: Model) -> ContactTable:
    """The contacts of ``model`` as a :class:`ContactTable`."""
    dof = np.array([c.dof for c in model.contacts], dtype=np.int64)
    side = np.array([c.side for c in model.contacts], dtype=np.int64)
    gap = np.array([c.gap for c in model.contacts], dtype=float)
    dofs: list[int] = []
    for d in dof.tolist():
        if d not in dofs:
            dofs.append(d)
    dofs_arr = np.array(dofs, dtype=np.int64)
    slot = np.array([dofs.index(d) for d in dof.tolist()], dtype=np.int64)
    c = set(model.c.tolist())
    massless = np.array([d in c for d in dof.tolist()], dtype=bool)
    return ContactTable(dof, side, gap, dofs_arr, slot, massless)


def static_contact_stiffness(model: Model) -> np.ndarray:
    """The static stiffness of the structure at each contact, k_i = 1/(e_iᵀ K⁻¹ e_i) (N/m),
    shape (n_ct,): the force that moves the contact DOF by a unit displacement with every
    other DOF free and every contact open.

    When every contact DOF is massless it is computed, as in mmshbm 0.1, from the
    condensed static stiffness of the massless DOFs, ``(w_iᵀ D_0⁻¹ w_i)⁻¹`` with
    ``D_0 = K_cc − K_cl K_ll⁻¹ K_lc`` (the same number: D_0⁻¹ is the c-block of K⁻¹).
    Otherwise (a contact DOF carries mass, as in models exported by FE packages) from a
    sparse LU factorisation of the whole K, one solve per distinct contact DOF.
    """
    table = contact_table(model)
    if model.massless_contacts:
        from ..harmonic.condense import Condensation

        D0 = Condensation(model).D0
        c = model.c
        out = np.empty(table.n)
        for i in range(table.n):
            w = np.zeros(len(c))
            w[int(np.searchsorted(c, table.dof[i]))] = -float(table.side[i])
            out[i] = 1.0 / float(w @ np.linalg.solve(D0, w))
        return out
    lu = spla.splu(sp.csc_matrix(model.K), permc_spec="MMD_AT_PLUS_A")
    E = np.zeros((model.n_dof, len(table.dofs)))
    E[table.dofs, np.arange(len(table.dofs))] = 1.0
    X = lu.solve(E)
    flex = X[table.dofs, np.arange(len(table.dofs))]
    return 1.0 / flex[table.slot]


def penalty_values(model: Model, value, stiffness: np.ndarray | None = None) -> np.ndarray:
    """Penalty stiffness k_p (N/m) of each contact, shape (n_ct,): ``value`` (one number for
    all or one per contact), or by default ``DEFAULT_PENALTY_FACTOR`` times the static
    stiffness at each contact (``stiffness``, computed when not given).

    Raises
    ------
    ValueError, TypeError
        Naming ``penalty_stiffness`` (or its entry): not positive and finite, or a
        sequence whose length is not the number of contacts.
    """
    from .. import _validate as check

    n_ct = model.n_contacts
    if value is None:
        return DEFAULT_PENALTY_FACTOR * (static_contact_stiffness(model) if stiffness is None else stiffness)
    if np.ndim(value) == 0:
        return np.full(n_ct, check.positive("penalty_stiffness", value))
    values = list(np.asarray(value, dtype=object).ravel())
    if np.ndim(value) != 1 or len(values) != n_ct:
        raise ValueError(f"penalty_stiffness must be one number or one per contact ({n_ct}), got {value!r}")
    return np.array([check.positive(f"penalty_stiffness[{i}]", v) for i, v in enumerate(values)])


def contact_law(model: Model, kp: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The contacts in terms of the DOFs with mass: free gaps ``h = gap + A q_l``, the LCP
    ``g = h + G λ >= 0, λ >= 0, gᵀλ = 0`` at fixed q_l, and the massless DOFs
    ``q_c = B q_l + E λ`` (B = −K_cc⁻¹ K_cl, the open recovery).

    A massless contact i (w_i = −side_i e_dof in c): A_i = −(K_lc K_cc⁻¹ w_i)ᵀ,
    G_ij = w_iᵀ K_cc⁻¹ w_j, E_:i = K_cc⁻¹ w_i. A contact on a DOF with mass is a penalty
    spring ``kp[i]``: A_i = −side_i e_dof (in l), G_ii = 1/k_p, E_:i = 0 (λ = k_p max(0, −h)
    solves its row of the LCP).

    Returns A (n_ct, n_l) in ``model.l`` order, E (n_c, n_ct), G (n_ct, n_ct).
    """
    import scipy.linalg as la

    table = contact_table(model)
    b = model.blocks
    c, l = model.c, model.l
    n_ct, n_c = table.n, len(c)
    A = np.zeros((n_ct, len(l)))
    W = np.zeros((n_c, n_ct))
    for i in range(n_ct):
        if table.massless[i]:
            W[int(np.searchsorted(c, table.dof[i])), i] = -float(table.side[i])
        else:
            A[i, int(np.searchsorted(l, table.dof[i]))] = -float(table.side[i])
    E = la.solve(b["K_cc"], W) if n_c else np.zeros((0, n_ct))
    G = W.T @ E
    heavy = ~table.massless
    if heavy.any():
        G[np.ix_(heavy, heavy)] = np.diag(1.0 / np.asarray(kp)[heavy])
    for i in np.flatnonzero(table.massless):
        A[i] = -b["K_lc"] @ E[:, i]
    return A, E, G


def start_mode(model: Model, mode: int) -> tuple[float, np.ndarray]:
    """Frequency (Hz) and shape (all DOFs, shape (n_dof,)) of the linear mode a branch
    starts from.

    With one contact this is ``model.linear_modes(mode)``'s last mode as it is (oriented
    so that the contact DOF first moves toward its stop). With several contacts a
    degenerate mode (e.g. identical uncoupled substructures) is made definite: within the
    eigenspace of ``mode`` (frequencies equal to 1e-8) the combination that moves
    ``model.amplitude_dof`` most is taken; the shape is then oriented so that the first
    contact whose DOF moves goes toward its stop.

    Raises
    ------
    ValueError
        If the mode does not move the amplitude DOF (then the branch has no amplitude).
    """
    if model.n_contacts == 1:
        freqs, modes = model.linear_modes(mode)
        return float(freqs[-1]), modes[:, -1]
    amp = model.amplitude_dof
    n_l = len(model.l)
    n_more = min(n_l, mode + 2)
    freqs, modes = model.linear_modes(n_more)
    f = freqs[mode - 1]
    same = np.flatnonzero(np.abs(freqs - f) <= _DEGENERATE_REL * f)
    if len(same) > 1 and same[-1] == n_more - 1 and n_more < n_l:
        freqs, modes = model.linear_modes(min(n_l, n_more + 8))
        same = np.flatnonzero(np.abs(freqs - f) <= _DEGENERATE_REL * f)
    if len(same) == 1:
        phi = modes[:, mode - 1].copy()
    else:
        basis = modes[:, same]
        weights = basis[amp]
        norm = np.linalg.norm(weights)
        phi = basis @ (weights / norm) if norm > 0 else modes[:, mode - 1].copy()
    scale = np.max(np.abs(phi))
    if abs(phi[amp]) <= 1e-12 * scale:
        raise ValueError(f"linear mode {mode} does not move the amplitude DOF {amp}: choose another "
                         "amplitude_dof or mode")
    for c in model.contacts:
        if abs(phi[c.dof]) > 1e-12 * scale:
            if phi[c.dof] * c.side < 0:
                phi = -phi
            break
    return float(f), phi
