"""One compiled evaluation of the friction forced response: residual and Jacobian of the
condensed system in scaled unknowns, called once per Newton iteration.

:func:`_forced_friction_evaluate` chains, without Python in between, what
:meth:`~mmshbm.methods.mms.friction_forced.FrictionForcedProblem._evaluate` does in steps:
the modal condensation at Ω (:func:`~mmshbm.methods.mms.condensation._damped_modal_kernels._damped_modal`:
D_k and P̂_1 with their Ω derivatives), the load σ(Ω) P̂_1 on harmonic 1, the unilateral
rows (:func:`~mmshbm.methods.mms.contact_kernels._damped_residual`, which leaves F = 𝔇x − load
and its derivatives on every other row), the friction rows in place
(:func:`~mmshbm.methods.mms._friction_kernels._friction_rows`: the play form, its AFT-free
exact projection), harmonic 1 of the amplitude DOF recovered from x
(:func:`~mmshbm.methods.mms._friction_kernels._tracked_harmonic`) and the scaling of rows
and columns. The caller owns every buffer (preallocated once per problem).

:func:`_forced_friction_record` is the per-point record of the same problems in one call:
the force F the structure needs at the massless DOFs, every DOF's coefficients (the DOFs
with mass by one complex solve per harmonic), the mean energy, and per friction node its
slip fraction and the work of its friction force over the period.

Kernels only; plain contiguous arrays. Cross-file callees are safe under the package's
cache policy (:mod:`mmshbm._kernel_cache`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..._kernel_cache import JIT_OPTIONS
from ..._kernel_cache import install as _install_cache_policy
from ...contact.coulomb_play_kernels import _play_projection
from ._friction_kernels import _tracked_harmonic
from .condensation._damped_modal_kernels import _damped_modal
from .contact_kernels import _block_times, _damped_residual

__all__: list[str] = []

_install_cache_policy()


@njit(**JIT_OPTIONS)
def _friction_rows_blocks(x, rows, n_c, slip_force, rho, tau, cos_t, sin_t, jacobian, R, Jx, Jp, slip):
    """:func:`~mmshbm.methods.mms._friction_kernels._friction_rows` (same arguments, same
    formulas) for Jx whose friction rows hold ∂F/∂x = 𝔇's rows: block diagonal in the
    harmonics, so row m (harmonic k) of DOF i has nonzeros only in harmonic k's columns, and
    the product (I + J_g/ρ) 𝔇 runs over those (2 n_c per row instead of n_x)."""
    n_x = x.shape[0]
    n = n_x // n_c
    n_p = Jp.shape[1]
    y = np.empty(n)
    g = np.empty(n)
    Jg = np.empty((n, n)) if jacobian else np.empty((0, 0))
    Ab = np.empty((n, 2 * n_c)) if jacobian else np.empty((0, 0))
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
        # the nonzero blocks of the rows of ∂F (harmonic k of row m: columns c0 .. c0 + w)
        for m in range(n):
            row = m * n_c + i
            c0 = 0 if m == 0 else (2 * ((m + 1) // 2) - 1) * n_c
            w = n_c if m == 0 else 2 * n_c
            for b in range(w):
                Ab[m, b] = Jx[row, c0 + b]
            for p in range(n_p):
                Ap[m, p] = Jp[row, p]
        for m in range(n):
            row = m * n_c + i
            for mm in range(n):
                wt = Jg[m, mm] / r
                if wt == 0.0:
                    continue
                c0 = 0 if mm == 0 else (2 * ((mm + 1) // 2) - 1) * n_c
                w = n_c if mm == 0 else 2 * n_c
                for b in range(w):
                    Jx[row, c0 + b] += wt * Ab[mm, b]
                for p in range(n_p):
                    Jp[row, p] += wt * Ap[mm, p]
            for b in range(n):
                Jx[row, b * n_c + i] -= Jg[m, b]


@njit(**JIT_OPTIONS)
def _forced_friction_evaluate(u, colscale, rowscale, length, H, power,
                              w2, gamma, Pc, Kinv, D0, beta,
                              rows, lo, hi, rr, exact, cos_u, sin_u, tau_u,
                              frows, slip_force, rho, tau_f, cos_f, sin_f,
                              K_ll, M_ll, C_ll, rhs, track,
                              jacobian, D, dD, dDx, P, dP, dPx, load, dload, Rx, Jx, Jp, slip, zy, dzy,
                              R, J):
    """Scaled residual R (n_x + 2,) and, with ``jacobian``, J (n_x + 2, n_x + 3) of the
    friction forced response with the amplitude DOF's harmonic 1 tracked, in place.

    u        : (n_x + 3,) scaled unknowns [x, a_1, b_1, Ω]; colscale (n_x + 3,) their units
               (m, m, m, rad/s); rowscale (n_x,) the rows' units (N); length (m)
    H, power : harmonics; σ(Ω) = Ω**power scales the load
    w2 … beta: the modal condensation's data (``_damped_modal``), beta (n_m, n_b), load column 0
    rows … tau_u : the unilateral contacts (``_damped_residual``; empty without them)
    frows … sin_f : the friction contacts (``_friction_rows``)
    K_ll … track : the tracked harmonic (``_tracked_harmonic``), ``track`` its row in l
    D … dzy  : work buffers of the shapes the callees take (dD (1, H+1, n_c, n_c), Jp (n_x, 1),
               dload (n_x, 1), zy and dzy (n_c + 1,))
    Returns the condensation's status (0 = evaluated; nonzero: singular, outputs incomplete).
    """
    n_x = Rx.shape[0]
    n_c = D.shape[1]
    omega = u[n_x + 2] * colscale[n_x + 2]
    status = _damped_modal(omega, 0.0, H, w2, gamma, Pc, Kinv, D0, beta, jacobian, False,
                           D, dD[0], dDx, P, dP, dPx)
    if status != 0:
        return status
    s = omega ** power
    ds = power * omega ** (power - 1) if power != 0 else 0.0
    x = np.empty(n_x)
    for a in range(n_x):
        x[a] = u[a] * colscale[a]
        load[a] = 0.0
        dload[a, 0] = 0.0
    for i in range(n_c):
        v = s * P[i, 0]
        load[n_c + i] = v.real
        load[2 * n_c + i] = -v.imag
        if jacobian:
            dv = s * dP[i, 0] + ds * P[i, 0]
            dload[n_c + i, 0] = dv.real
            dload[2 * n_c + i, 0] = -dv.imag
    _damped_residual(D, dD, x, load, dload, rows, lo, hi, rr, exact, cos_u, sin_u, tau_u, jacobian,
                     Rx, Jx, Jp)
    _friction_rows_blocks(x, frows, n_c, slip_force, rho, tau_f, cos_f, sin_f, jacobian, Rx, Jx, Jp, slip)
    _tracked_harmonic(K_ll, M_ll, C_ll, rhs, track, omega, jacobian, zy, dzy)
    # harmonic 1 of the tracked DOF: q = −z·(U_c − i U_s) + σ y, recorded as (Re q, −Im q)
    q = s * zy[n_c]
    dq = ds * zy[n_c] + s * dzy[n_c] if jacobian else 0.0j
    for j in range(n_c):
        U = complex(x[n_c + j], -x[2 * n_c + j])
        q -= zy[j] * U
        if jacobian:
            dq -= dzy[j] * U
    for a in range(n_x):
        R[a] = Rx[a] / rowscale[a]
    R[n_x] = (u[n_x] * length - q.real) / length
    R[n_x + 1] = (u[n_x + 1] * length + q.imag) / length
    if not jacobian:
        return 0
    ws = colscale[n_x + 2]
    for a in range(n_x):
        ra = 1.0 / rowscale[a]
        for b in range(n_x):
            J[a, b] = Jx[a, b] * (colscale[b] * ra)
        J[a, n_x] = 0.0
        J[a, n_x + 1] = 0.0
        J[a, n_x + 2] = Jp[a, 0] * ws / rowscale[a]
    for r in range(2):
        for b in range(n_x + 3):
            J[n_x + r, b] = 0.0
    # ∂(Re q, −Im q)/∂x: q = −Σ z_j (x_c,j − i x_s,j)
    for j in range(n_c):
        zr = zy[j].real
        zi = zy[j].imag
        J[n_x, n_c + j] = zr * colscale[n_c + j] / length
        J[n_x, 2 * n_c + j] = zi * colscale[2 * n_c + j] / length
        J[n_x + 1, n_c + j] = -zi * colscale[n_c + j] / length
        J[n_x + 1, 2 * n_c + j] = zr * colscale[2 * n_c + j] / length
    J[n_x, n_x] = 1.0
    J[n_x + 1, n_x + 1] = 1.0
    J[n_x, n_x + 2] = -dq.real * ws / length
    J[n_x + 1, n_x + 2] = dq.imag * ws / length
    return 0


@njit(**JIT_OPTIONS)
def _forced_friction_record(x, omega, sigma, H, power, w2, gamma, Pc, Kinv, D0, beta,
                            frows, slip_force, rho, tau_f, cos_f, sin_f,
                            K_ll, M_ll, C_ll, K_lc, force_l, c_dofs, l_dofs, K, M,
                            D, dD, dDx, P, dP, dPx, F, Q, out):
    """The record of a converged point, in place.

    x        : (n_x,) coefficients of the massless DOFs (m); Ω (rad/s); σ the force's factor
    H … beta : as :func:`_forced_friction_evaluate` (the modal condensation)
    frows … sin_f : the friction contacts
    K_ll, M_ll, C_ll (n_l, n_l), K_lc (n_l, n_c), force_l (n_l,) complex F̂_l: the dense blocks
    c_dofs, l_dofs : (n_c,), (n_l,) int64 the massless DOFs and those with mass
    K, M     : (n_dof, n_dof) dense stiffness and mass
    D … dPx  : condensation buffers; F (n_x,) <- 𝔇x − σ σ(Ω) P̂ on harmonic 1 (N)
    Q        : (n_dof, 2H+1) <- NLvib-ordered coefficients of all DOFs (m)
    out      : (3,) <- mean energy (J), largest slip fraction, friction work per period (J)
    Returns 0, or the condensation's nonzero status; raises where some S_k is singular.
    """
    n_c = D.shape[1]
    n_l = K_ll.shape[0]
    n_dof = K.shape[0]
    n = 2 * H + 1
    status = _damped_modal(omega, 0.0, H, w2, gamma, Pc, Kinv, D0, beta, False, False, D, dD, dDx, P, dP, dPx)
    if status != 0:
        return status
    s = sigma * omega ** power
    _block_times(D, x, F)
    for i in range(n_c):
        v = s * P[i, 0]
        F[n_c + i] -= v.real
        F[2 * n_c + i] += v.imag
    # all coefficients: Q̂_l,k = S_k⁻¹ (σ F̂_l δ_k1 − K_lc Q̂_c,k), S_k = K_ll + ikΩ C_ll − (kΩ)² M_ll
    for i in range(n_c):
        for m in range(n):
            Q[c_dofs[i], m] = x[m * n_c + i]
    S = np.empty((n_l, n_l), dtype=np.complex128)
    rhs = np.empty((n_l, 1), dtype=np.complex128)
    for k in range(H + 1):
        w = k * omega
        for a in range(n_l):
            for b in range(n_l):
                S[a, b] = complex(K_ll[a, b] - w * w * M_ll[a, b], w * C_ll[a, b])
            acc = 0.0j
            for j in range(n_c):
                if k == 0:
                    acc -= K_lc[a, j] * x[j]
                else:
                    acc -= K_lc[a, j] * complex(x[(2 * k - 1) * n_c + j], -x[2 * k * n_c + j])
            if k == 1:
                acc += s * force_l[a]
            rhs[a, 0] = acc
        X = np.linalg.solve(S, rhs)
        for a in range(n_l):
            if k == 0:
                Q[l_dofs[a], 0] = X[a, 0].real
            else:
                Q[l_dofs[a], 2 * k - 1] = X[a, 0].real
                Q[l_dofs[a], 2 * k] = -X[a, 0].imag
    # mean energy: ½ q₀ᵀKq₀ + ¼ Σ_k (a_kᵀK a_k + b_kᵀK b_k) + ¼ Ω² Σ_k k² (a_kᵀM a_k + b_kᵀM b_k)
    energy = 0.0
    for m in range(n):
        kq = 0.0
        mq = 0.0
        for a in range(n_dof):
            acc_k = 0.0
            acc_m = 0.0
            for b in range(n_dof):
                acc_k += K[a, b] * Q[b, m]
                acc_m += M[a, b] * Q[b, m]
            kq += Q[a, m] * acc_k
            mq += Q[a, m] * acc_m
        if m == 0:
            energy += 0.5 * kq
        else:
            k = (m + 1) // 2
            energy += 0.25 * kq + 0.25 * omega * omega * k * k * mq
    # per friction node: slip fraction and the work ∮ f u′ dτ, f = −F_t, by Parseval
    y = np.empty(n)
    g = np.empty(n)
    Jg = np.empty((0, 0))
    slip = 0.0
    work = 0.0
    for t in range(frows.shape[0]):
        i = frows[t]
        for m in range(n):
            y[m] = x[m * n_c + i] - F[m * n_c + i] / rho[t]
        sl = _play_projection(y, slip_force[t], rho[t], tau_f, cos_f, sin_f, False, g, Jg)
        if sl > slip:
            slip = sl
        acc = 0.0
        for k in range(1, H + 1):
            c = (2 * k - 1) * n_c + i
            sn = 2 * k * n_c + i
            # u′: cos coefficient k s_k, sin coefficient −k c_k
            acc += -F[c] * (k * x[sn]) - F[sn] * (-k * x[c])
        work += np.pi * acc
    out[0] = energy
    out[1] = slip
    out[2] = work
    return 0
