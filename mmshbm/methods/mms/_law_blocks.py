"""The friction law's per-node blocks in one compiled pass (the play form, constant slip force).

The residual of :class:`~mmshbm.methods.mms.friction_rows.FrictionRows` on friction DOF t is
R_t = F_t − g_t(y_t), y_t = x_t − F_t/ρ_t, g the exact projection of the play operator
(:func:`~mmshbm.contact.coulomb_play_kernels._play_projection`). Its derivatives are
∂R_t/∂F_t = I + J_g/ρ and ∂R_t/∂x_t = −J_g, with J_g = ∂g/∂y ((2H+1) × (2H+1), coupling
only the harmonics of node t). :func:`_law_blocks` writes R on the friction rows and J_g per
node, never a row of the whole Jacobian: what :mod:`mmshbm.methods.mms.forced_operator`
multiplies by.

Kernels only; plain contiguous arrays.
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
def _law_blocks(x, rows, n_c, slip_force, rho, tau, cos_t, sin_t, jacobian, R, Jg, slip):
    """In place on the rows of the friction DOFs ``rows`` (int64 indices into the n_c
    massless DOFs; coefficient m of DOF i at m n_c + i):

    x      : (n_x,) NLvib-ordered coefficients of the massless DOFs (m)
    slip_force, rho : (n_f,) s = μN (N) and ρ (N/m) per friction DOF
    tau, cos_t, sin_t : the play projection's sample grid and tables
    R      : (n_x,) F (N) on entry on those rows, R_t on return
    Jg     : (n_f, 2H+1, 2H+1) <- ∂g/∂y per node (dimensionless × N/m: N/m), with ``jacobian``
    slip   : (n_f,) <- the fraction of the period each node slips
    """
    n = x.shape[0] // n_c
    y = np.empty(n)
    g = np.empty(n)
    scratch = np.empty((n, n))
    for t in range(rows.shape[0]):
        i = rows[t]
        r = rho[t]
        for m in range(n):
            y[m] = x[m * n_c + i] - R[m * n_c + i] / r
        if jacobian:
            slip[t] = _play_projection(y, slip_force[t], r, tau, cos_t, sin_t, True, g, scratch)
            for a in range(n):
                for b in range(n):
                    Jg[t, a, b] = scratch[a, b]
        else:
            slip[t] = _play_projection(y, slip_force[t], r, tau, cos_t, sin_t, False, g, scratch)
        for m in range(n):
            R[m * n_c + i] -= g[m]
