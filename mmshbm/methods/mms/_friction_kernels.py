"""The friction rows of MMS-HBM in one compiled pass (the play form, constant slip force).

The residual of :class:`~mmshbm.methods.mms.friction_rows.FrictionRows` replaces the rows
F_t = 0 of each friction DOF t by R_t = F_t − proj[ρ (Play(y) − y)], y = x_t − F_t/ρ, with
∂R_t/∂x = (I + J_g/ρ) ∂F_t/∂x − J_g on x_t's own columns and ∂R_t/∂params = (I + J_g/ρ)
∂F_t/∂params, J_g = ∂g/∂y (:func:`~mmshbm.contact.coulomb_play_kernels._play_projection`).
:func:`_friction_rows` applies this in place to arrays that hold F, ∂F/∂x and ∂F/∂params
on those rows (what :func:`~mmshbm.methods.mms.contact_kernels._damped_residual` leaves on every
row that is not a unilateral contact), so the fused unilateral residual and these rows make
the whole residual and Jacobian without Python in between.

:func:`_tracked_harmonic` is the solve of
:class:`~mmshbm.methods.mms.friction_tracked.TrackedHarmonic` (harmonic 1 of the amplitude
DOF with its Ω derivative).

Kernels only; plain contiguous arrays. :func:`_friction_rows` calls the play projection of
:mod:`mmshbm.contact.coulomb_play_kernels` (the package's cache policy,
:mod:`mmshbm._kernel_cache`, recompiles it when that file changes).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..._kernel_cache import JIT_OPTIONS
from ..._kernel_cache import install as _install_cache_policy
from ...contact.coulomb_play_kernels import _play_projection

__all__: list[str] = []

_install_cache_policy()


@njit(**JIT_OPTIONS)
def _friction_rows(x, rows, n_c, slip_force, rho, tau, cos_t, sin_t, jacobian, R, Jx, Jp, slip):
    """In place on the rows of the friction DOFs ``rows`` (int64, indices into the massless
    DOFs, n_c of them; coefficient m of DOF i at m n_c + i):

    x      : (n_x,) NLvib-ordered coefficients of the massless DOFs, n_x = (2H+1) n_c
    slip_force, rho : (n_f,) s = μN (N) and ρ (N/m) per friction DOF
    tau, cos_t, sin_t : the play projection's sample grid (N,) and tables (H+1, N)
    R      : (n_x,) F on entry on those rows, R_t on return
    Jx, Jp : (n_x, n_x), (n_x, n_p) ∂F/∂x, ∂F/∂params on entry, ∂R/∂x, ∂R/∂params on
             return (read and written only with ``jacobian``)
    slip   : (n_f,) <- the fraction of the period each node slips
    """
    n_x = x.shape[0]
    n = n_x // n_c
    n_p = Jp.shape[1]
    y = np.empty(n)
    g = np.empty(n)
    Jg = np.empty((n, n)) if jacobian else np.empty((0, 0))
    Ax = np.empty((n, n_x)) if jacobian else np.empty((0, 0))
    Ap = np.empty((n, n_p)) if jacobian else np.empty((0, 0))
    for t in range(rows.shape[0]):
        i = rows[t]
        r = rho[t]
        for m in range(n):
            y[m] = x[m * n_c + i] - R[m * n_c + i] / r
        slip[t] = _play_projection(y, slip_force[t], r, tau, cos_t, sin_t, jacobian, g, Jg)
        for m in range(n):
            R[m * n_c + i] -= g[m]
        if not jacobian:
            continue
        # (I + J_g/ρ) times the rows of ∂F, from a copy of them
        for m in range(n):
            for b in range(n_x):
                Ax[m, b] = Jx[m * n_c + i, b]
            for p in range(n_p):
                Ap[m, p] = Jp[m * n_c + i, p]
        for m in range(n):
            row = m * n_c + i
            for mm in range(n):
                w = Jg[m, mm] / r
                if w == 0.0:
                    continue
                for b in range(n_x):
                    Jx[row, b] += w * Ax[mm, b]
                for p in range(n_p):
                    Jp[row, p] += w * Ap[mm, p]
            for b in range(n):
                Jx[row, b * n_c + i] -= Jg[m, b]


@njit(**JIT_OPTIONS)
def _tracked_harmonic(K_ll, M_ll, C_ll, rhs, row, omega, derivative, z, dz):
    """Harmonic 1 of DOF ``row`` of the DOFs with mass recovered from the massless DOFs
    (:class:`~mmshbm.methods.mms.friction_tracked.TrackedHarmonic`): with
    S_1 = K_ll + iΩ C_ll − Ω² M_ll (n_l, n_l) and the right-hand sides ``rhs`` = [e_t, K_lc,
    F̂_l] (n_l, n_c + 2) complex, writes z <- [(S_1⁻¹K_lc)_t, (S_1⁻¹F̂_l)_t] (n_c + 1,) and
    with ``derivative`` dz <- their Ω derivatives −wᵀ S′ S_1⁻¹[K_lc, F̂_l], w = S_1⁻¹e_t,
    S′ = i C_ll − 2Ω M_ll (S_1 and S′ symmetric). Raises where S_1 is singular."""
    n_l = K_ll.shape[0]
    S = np.empty((n_l, n_l), dtype=np.complex128)
    for i in range(n_l):
        for j in range(n_l):
            S[i, j] = complex(K_ll[i, j] - omega * omega * M_ll[i, j], omega * C_ll[i, j])
    X = np.linalg.solve(S, rhs)
    m = rhs.shape[1] - 1
    for c in range(m):
        z[c] = X[row, c + 1]
    if not derivative:
        return
    wdS = np.zeros(n_l, dtype=np.complex128)
    for j in range(n_l):
        acc = 0j
        for i in range(n_l):
            acc += X[i, 0] * complex(-2.0 * omega * M_ll[i, j], C_ll[i, j])
        wdS[j] = acc
    for c in range(m):
        acc = 0j
        for j in range(n_l):
            acc += wdS[j] * X[j, c + 1]
        dz[c] = -acc
