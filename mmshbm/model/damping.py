"""Viscous damping of a model: modal damping ratios or Rayleigh damping.

The damping force ``C q'`` acts on the DOFs with mass ``l`` only: the massless DOFs
``c`` are static (their equations have neither inertia nor damping), so C has zero rows
and columns there (``Model.from_matrices`` refuses a C that couples them).

Two standard forms, which may be combined (the matrices add):

**Modal damping ratios** ζ_j. With (ω_j, φ_j) the mass-normalised modes of the
structure with the contacts open (``model.linear_modes``: the massless DOFs condensed
statically, φ_jᵀ M_ll φ_k = δ_jk on the DOFs with mass),

    C_ll = Σ_j 2 ζ_j ω_j (M_ll φ_j)(M_ll φ_j)ᵀ,       so that   φ_jᵀ C_ll φ_k = 2 ζ_j ω_j δ_jk:

mode j of the open structure decays with ratio ζ_j exactly. One ratio for every mode,
or a sequence (ζ_1, ..., ζ_m) for the m lowest modes; the modes above m are undamped
(ζ_j = 0). C_ll is dense (every mode couples every DOF).

**Rayleigh damping** α M + β K restricted to the DOFs with mass. The stiffness-proportional
force β K q' of the whole model has rows on the massless DOFs, β(K_cl q_l' + K_cc q_c'),
which would make them dynamic. With the massless DOFs following statically (contacts
open: q_c = −K_cc⁻¹ K_cl q_l) that row vanishes and the force on the DOFs with mass is
β(K_ll q_l' + K_lc q_c') = β K_open q_l', with K_open = K_ll − K_lc K_cc⁻¹ K_cl the
statically condensed stiffness (``model.reduced_stiffness``; sparse, the pattern of
K_ll). So

    C_ll = α M_ll + β K_open,       ζ_j = α/(2 ω_j) + β ω_j / 2   exactly for the open modes.

(Taking K_ll instead, the stiffness with the massless DOFs clamped, would damp the stiff
tip element as if its tip were held: on the default beam, β = 1e-5 s would give the
first mode a ratio of 190 instead of 0.009.)
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp

from .. import _validate as check

__all__ = ["damping_matrix", "modal_damping_ratios", "model_has_damping", "DISSIPATIVE_ATTRIBUTES"]


def _ratios(modal_ratio, n_l: int) -> np.ndarray:
    """Modal damping ratios as an array: one number for all n_l modes, or a sequence."""
    if isinstance(modal_ratio, bool):
        raise TypeError(f"modal_ratio must be a number or a sequence of numbers, got {modal_ratio!r}")
    if isinstance(modal_ratio, numbers.Real):
        zeta = check.real_number("modal_ratio", modal_ratio)
        if zeta < 0:
            raise ValueError(f"modal_ratio must be >= 0 (negative damping feeds energy in), "
                             f"got {modal_ratio!r}")
        return np.full(n_l, zeta)
    if isinstance(modal_ratio, str | bytes) or not isinstance(modal_ratio, Sequence | np.ndarray):
        raise TypeError(f"modal_ratio must be a number or a sequence of numbers, got {modal_ratio!r}")
    values = list(np.asarray(modal_ratio, dtype=object).ravel()) if isinstance(modal_ratio, np.ndarray) \
        else list(modal_ratio)
    if not values:
        raise ValueError("modal_ratio is an empty sequence: give one ratio, or one per mode")
    if len(values) > n_l:
        raise ValueError(f"modal_ratio has {len(values)} ratios but the model has only {n_l} modes "
                         "(DOFs with mass)")
    zeta = np.zeros(n_l)
    for j, v in enumerate(values):
        zeta[j] = check.real_number(f"modal_ratio[{j}]", v)
        if zeta[j] < 0:
            raise ValueError(f"modal_ratio[{j}] must be >= 0 (negative damping feeds energy in), got {v!r}")
    return zeta


def damping_matrix(model, modal_ratio=None, rayleigh=None) -> sp.csr_matrix:
    """The damping matrix C (N·s/m) of ``model`` on all its DOFs, zero on the massless ones.

    Parameters
    ----------
    model : Model
    modal_ratio : float or sequence of float, optional
        Modal damping ratio ζ >= 0 of every mode of the open-contact structure, or
        (ζ_1, ..., ζ_m) for the m lowest modes (the others undamped).
    rayleigh : (float, float), optional
        (α in 1/s, β in s), both >= 0: C_ll = α M_ll + β K_open.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (n_dof, n_dof)
        Symmetric positive semidefinite; the sum of the two forms when both are given.

    Raises
    ------
    ValueError, TypeError
        Neither form given, a negative or non-finite ratio or coefficient, more ratios
        than modes, a malformed ``rayleigh`` pair.
    """
    if modal_ratio is None and rayleigh is None:
        raise ValueError("give modal_ratio=... (one ratio or one per mode) and/or rayleigh=(alpha, beta)")
    l = model.l
    n_l = len(l)
    b = model.blocks
    C_ll = sp.csc_matrix((n_l, n_l))
    if rayleigh is not None:
        if isinstance(rayleigh, str | bytes) or not isinstance(rayleigh, Sequence | np.ndarray) \
                or len(rayleigh) != 2:
            raise ValueError(f"rayleigh must be a pair (alpha, beta), got {rayleigh!r}")
        alpha = check.real_number("rayleigh alpha", rayleigh[0])
        beta = check.real_number("rayleigh beta", rayleigh[1])
        for name, v in (("alpha", alpha), ("beta", beta)):
            if v < 0:
                raise ValueError(f"rayleigh {name} must be >= 0 (negative damping feeds energy in), "
                                 f"got {v!r}")
        C_ll = C_ll + alpha * b["M_ll"] + beta * model.reduced_stiffness
    if modal_ratio is not None:
        zeta = _ratios(modal_ratio, n_l)
        m = int(np.max(np.flatnonzero(zeta > 0))) + 1 if np.any(zeta > 0) else 0
        if m:
            freqs, modes = model.linear_modes(m)
            MPhi = b["M_ll"] @ modes[l]  # (n_l, m)
            weights = 2.0 * zeta[:m] * (2 * np.pi * freqs)
            C_modal = (MPhi * weights) @ MPhi.T
            C_ll = C_ll + sp.csc_matrix(0.5 * (C_modal + C_modal.T))
    C_ll = sp.coo_matrix(C_ll)
    C = sp.coo_matrix((C_ll.data, (l[C_ll.row], l[C_ll.col])), shape=(model.n_dof, model.n_dof)).tocsr()
    C.sum_duplicates()
    return C


def modal_damping_ratios(model, n: int = 1) -> np.ndarray:
    """Damping ratios φ_jᵀ C φ_j / (2 ω_j) of the ``n`` lowest open-contact modes (φ_j
    mass-normalised); exact modal ratios for proportional (modal or Rayleigh on the
    stiffness) damping, the first-order estimate for any other light damping.

    Returns
    -------
    ndarray, shape (n,)
        Dimensionless ratios; zeros for an undamped model.
    """
    freqs, modes = model.linear_modes(n)
    if model.damping is None:
        return np.zeros(len(freqs))
    C = model.damping
    return np.einsum("ij,ij->j", modes, C @ modes) / (2.0 * 2 * np.pi * freqs)


#: model attributes besides the viscous matrix ``damping`` that dissipate energy when they
#: are set (not None, not empty): :func:`model_has_damping` counts them as damping
DISSIPATIVE_ATTRIBUTES = ("friction",)


def model_has_damping(model) -> bool:
    """Whether ``model`` dissipates energy: a viscous damping matrix with a nonzero entry,
    or one of :data:`DISSIPATIVE_ATTRIBUTES` set (e.g. a non-empty tuple of friction
    contacts). A forced response needs it (undamped, the response grows along the
    backbone without bound)."""
    C = getattr(model, "damping", None)
    if C is not None and (C.count_nonzero() if sp.issparse(C) else np.count_nonzero(C)) > 0:
        return True
    for name in DISSIPATIVE_ATTRIBUTES:
        value = getattr(model, name, None)
        if value is not None and (len(value) > 0 if hasattr(value, "__len__") else True):
            return True
    return False
