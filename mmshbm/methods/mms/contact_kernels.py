"""The MMS-HBM residuals with the unilateral contact law fused in: the conservative
(cosine) residual with its Jacobian and monitor, and the contact rows of the damped
residual. The law and its projection are :mod:`mmshbm.contact.unilateral` and
:mod:`mmshbm.contact.projection`; these kernels call their kernels on each contact DOF.

Per contact DOF with admissible positions [lo, hi], needed force f and displacement q,
the residual rows are the harmonic projection of f + r [(p − hi)₊ − (lo − p)₊],
p = q − f/r (:mod:`mmshbm.contact.unilateral`); with the spectra C of the active sets
{p > hi} and {p < lo} (:mod:`mmshbm.contact.projection`) the projection of s·p is the
matrix G_mk = ε_m/2 (C_|m−k| + C_m+k) times the coefficients of p, the exact Jacobian
when the switching instants are located (docs/design.md §2, §8).

The kernels take plain arrays and know nothing of models. They call kernels of other
files; the package's cache policy (:mod:`mmshbm._kernel_cache`) recompiles them when any
kernel file changes.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...contact.projection import _spectrum
from ...contact.unilateral import _project
from ...core.measures import _series_peak
from ...harmonic.kernels import JIT_OPTIONS

__all__: list[str] = []  # kernels only; the projections as functions: mmshbm.contact.unilateral

# ---------------------------------------------------------------------- fused MMS-HBM
@njit(**JIT_OPTIONS)
def _mmshbm_eval(D, dD, a, eta, omega, pole_k, pole_b, pole_w2, cdof, lo, hi, r, exact, cos_table, sin_table,
                 tau_t, rowscale, colscale, jacobian, R, J, F, dF, pc, ps, gc, g_t, dg_t, roots, C_hi, C_lo,
                 S_w, P):
    """Scaled cosine-only MMS-HBM residual (and Jacobian) for any number of contact DOFs,
    with the poles of D_k carried by extra unknowns η (:mod:`mmshbm.methods.mms.condensation.poles`).

    D, dD     : (H+1, n_c, n_c) condensed dynamic stiffness (its regular part for the
                harmonics with poles) and ∂D_k/∂Ω (dD read only if ``jacobian``)
    a         : (H+1, n_c) cosine coefficients of the massless DOFs (m, rad)
    eta, omega: (n_p,) pole unknowns η_jk; Ω (rad/s)
    pole_k, pole_b, pole_w2 : (n_p,) int harmonic k, (n_p, n_c) b_j, (n_p,) ω_j² per pole
    cdof      : (n_k,) int, positions inside ``c`` of the contact DOFs
    lo, hi, r : (n_k,) admissible interval (±inf: no stop) and proximal parameter (N/m)
    exact     : exact (C¹) or sampled projection
    cos_table : (2H+1, N) cos pτ_j; sin_table : (H+1, N) sin kτ_j; tau_t : (N,) τ_j
    rowscale  : (n_a + n_p,); colscale : (n_a + n_p + 1,), n_a = (H+1) n_c
    R         : (n_a + n_p,) output, scaled residual: rows m·n_c + i, then one per pole
    J         : (n_a + n_p, n_a + n_p + 1) output if ``jacobian``, scaled; columns a, η, Ω
    work      : F, dF (H+1, n_c); pc, ps, gc (H+1,); g_t, dg_t (N,); roots (2N+2,);
                C_hi, C_lo, S_w (2H+1,); P (H+1, H+1)

    F_k = D_k a_k − Σ_{poles of k} b_j η_jk is the force the structure needs at the
    massless DOFs. Rows of massless DOFs without a contact: F_k,i = 0. Rows of a contact
    DOF: proj_m[f + r s (p − θ)] with p = q − f/r (module docstring). Pole rows:
    (ω_j² − (kΩ)²) η_jk − b_jᵀ a_k = 0.
    """
    H1 = D.shape[0]
    n_c = D.shape[1]
    n_a = H1 * n_c
    n_p = eta.shape[0]
    n_r = n_a + n_p
    n_om = n_r
    for k in range(H1):
        for i in range(n_c):
            f = 0.0
            for q in range(n_c):
                f += D[k, i, q] * a[k, q]
            F[k, i] = f
            if jacobian:
                df = 0.0
                for q in range(n_c):
                    df += dD[k, i, q] * a[k, q]
                dF[k, i] = df
    for p in range(n_p):
        k = pole_k[p]
        for i in range(n_c):
            F[k, i] -= pole_b[p, i] * eta[p]
    for k in range(H1):
        for i in range(n_c):
            R[k * n_c + i] = F[k, i]
    if jacobian:
        for row in range(n_r):
            for col in range(n_r + 1):
                J[row, col] = 0.0
        for k in range(H1):
            for i in range(n_c):
                for j in range(n_c):
                    J[k * n_c + i, k * n_c + j] = D[k, i, j]
                J[k * n_c + i, n_om] = dF[k, i]
        for p in range(n_p):
            k = pole_k[p]
            for i in range(n_c):
                J[k * n_c + i, n_a + p] = -pole_b[p, i]
    for ps_i in range(ps.shape[0]):
        ps[ps_i] = 0.0
    n_spec = C_hi.shape[0]
    for ic in range(cdof.shape[0]):
        i = cdof[ic]
        ri = r[ic]
        for k in range(H1):
            pc[k] = a[k, i] - F[k, i] / ri
        for s_i in range(n_spec):
            C_hi[s_i] = 0.0
            C_lo[s_i] = 0.0
        if hi[ic] < np.inf:
            for k in range(H1):
                gc[k] = pc[k]
            gc[0] -= hi[ic]
            _spectrum(gc, ps, cos_table, sin_table, tau_t, exact, g_t, dg_t, roots, C_hi, S_w)
        if lo[ic] > -np.inf:
            for k in range(H1):
                gc[k] = -pc[k]
            gc[0] += lo[ic]
            _spectrum(gc, ps, cos_table, sin_table, tau_t, exact, g_t, dg_t, roots, C_lo, S_w)
        # P = G of the whole active set; residual rows m of DOF i
        for m in range(H1):
            em = 1.0 if m == 0 else 2.0
            acc = 0.0
            for k in range(H1):
                d = m - k if m >= k else k - m
                P[m, k] = 0.5 * em * (C_hi[d] + C_lo[d] + C_hi[m + k] + C_lo[m + k])
                acc += P[m, k] * pc[k]
            if C_hi[m] != 0.0:
                acc -= hi[ic] * em * C_hi[m]
            if C_lo[m] != 0.0:
                acc -= lo[ic] * em * C_lo[m]
            R[m * n_c + i] = F[m, i] + ri * acc
        if jacobian:
            # ∂R_m = Σ_k (δ_mk − P_mk) ∂F_k,i + r P_mk ∂a_k,i
            for m in range(H1):
                row = m * n_c + i
                dOmega = 0.0
                for k in range(H1):
                    w = (1.0 if m == k else 0.0) - P[m, k]
                    for j in range(n_c):
                        J[row, k * n_c + j] = w * D[k, i, j]
                    J[row, k * n_c + i] += ri * P[m, k]
                    dOmega += w * dF[k, i]
                J[row, n_om] = dOmega
                for p in range(n_p):
                    k = pole_k[p]
                    w = (1.0 if m == k else 0.0) - P[m, k]
                    J[row, n_a + p] = -w * pole_b[p, i]
    for p in range(n_p):
        k = pole_k[p]
        kw = k * omega
        ba = 0.0
        for q in range(n_c):
            ba += pole_b[p, q] * a[k, q]
        R[n_a + p] = (pole_w2[p] - kw * kw) * eta[p] - ba
        if jacobian:
            for q in range(n_c):
                J[n_a + p, k * n_c + q] = -pole_b[p, q]
            J[n_a + p, n_a + p] = pole_w2[p] - kw * kw
            J[n_a + p, n_om] = -2.0 * k * k * omega * eta[p]
    for row in range(n_r):
        R[row] /= rowscale[row]
    if jacobian:
        for row in range(n_r):
            for col in range(n_r + 1):
                J[row, col] = J[row, col] * colscale[col] / rowscale[row]


@njit(**JIT_OPTIONS)
def _mmshbm_monitor_multi(D, dD, a, eta, pole_k, pole_b, cdof, lo, hi, r, omega, amp_row, amp_sign, cos_table,
                          sin_table, c_w, s_w, y_t, out):
    """Amplitude, mean energy and peak contact force of a cosine MMS-HBM point.

    eta, pole_k, pole_b : pole unknowns and their harmonic and b_j (see ``_mmshbm_eval``);
               D, dD are then the regular parts
    amp_row  : (H+1,) cosine coefficients of the amplitude DOF's motion
    amp_sign : +1/−1: amplitude = max of amp_sign·q over the period (a single one-sided
               contact: the excursion away from the stop); 0: max |q|
    cos_table, sin_table : (>= H+1, N) cos kτ_j, sin kτ_j on the problem's sample grid
    c_w, s_w : (H+1,) work; y_t : (N,) work
    out      : (3,) <- [amplitude, energy (J), peak contact force (N, exactly 0 when the
               proximal active set is empty at every sample of every contact)]

    Peaks are located on the sample grid and refined by Newton on the series' derivative,
    so they are exact to round-off.
    """
    H1 = D.shape[0]
    n_c = D.shape[1]
    N = y_t.shape[0]
    quad0 = 0.0
    quad = 0.0
    quad_m = 0.0
    for k in range(H1):
        qk = 0.0
        qm = 0.0
        for i in range(n_c):
            f = 0.0
            df = 0.0
            for j in range(n_c):
                f += D[k, i, j] * a[k, j]
                df += dD[k, i, j] * a[k, j]
            qk += a[k, i] * f
            qm += a[k, i] * df
        for p in range(pole_k.shape[0]):
            if pole_k[p] == k:
                ba = 0.0
                for i in range(n_c):
                    ba += pole_b[p, i] * a[k, i]
                qk -= eta[p] * ba
                qm -= 2.0 * k * k * omega * eta[p] * eta[p]
        if k == 0:
            quad0 = qk
        else:
            quad += qk
            quad_m += qm
    out[1] = 0.5 * quad0 + 0.25 * (quad - omega * quad_m)
    for k in range(H1):
        s_w[k] = 0.0
    if amp_sign != 0.0:
        for k in range(H1):
            c_w[k] = amp_sign * amp_row[k]
        out[0] = _series_peak(c_w, s_w, cos_table, sin_table, y_t)
    else:
        for k in range(H1):
            c_w[k] = amp_row[k]
        up = _series_peak(c_w, s_w, cos_table, sin_table, y_t)
        for k in range(H1):
            c_w[k] = -amp_row[k]
        down = _series_peak(c_w, s_w, cos_table, sin_table, y_t)
        out[0] = up if up > down else down
    peak = 0.0
    for ic in range(cdof.shape[0]):
        i = cdof[ic]
        # the force series f_i (with the pole unknowns' share)
        for k in range(H1):
            fk = 0.0
            for m in range(n_c):
                fk += D[k, i, m] * a[k, m]
            for p in range(pole_k.shape[0]):
                if pole_k[p] == k:
                    fk -= pole_b[p, i] * eta[p]
            c_w[k] = fk
        active_hi = False
        active_lo = False
        for j in range(N):
            q = 0.0
            f = 0.0
            for k in range(H1):
                q += a[k, i] * cos_table[k, j]
                f += c_w[k] * cos_table[k, j]
            pj = q - f / r[ic]
            if pj > hi[ic]:
                active_hi = True
            elif pj < lo[ic]:
                active_lo = True
        if active_hi:  # λ = −f at an upper stop
            for k in range(H1):
                c_w[k] = -c_w[k]
            v = _series_peak(c_w, s_w, cos_table, sin_table, y_t)
            for k in range(H1):
                c_w[k] = -c_w[k]
            if v > peak:
                peak = v
        if active_lo:  # λ = +f at a lower stop
            v = _series_peak(c_w, s_w, cos_table, sin_table, y_t)
            if v > peak:
                peak = v
    out[2] = peak


# ---------------------------------------------------------------------- damped MMS-HBM
@njit(**JIT_OPTIONS)
def _contact_rows(x, F, rows, n_c, lo, hi, rr, exact, cos_t, sin_t, tau, R, G):
    """The contact rows of the damped MMS-HBM residual (:mod:`mmshbm.methods.mms.damped`), in
    place: for contact j at massless DOF i = rows[j] with coefficients idx = m·n_c + i,
    R[idx] = F[idx] + r_j φ(p), p = x[idx] − F[idx]/r_j, and G[j] = ∂φ/∂p (2H+1, 2H+1)."""
    n = G.shape[1]
    p = np.empty(n)
    phi = np.empty(n)
    for j in range(rows.shape[0]):
        i = rows[j]
        rj = rr[j]
        for m in range(n):
            p[m] = x[m * n_c + i] - F[m * n_c + i] / rj
        _project(p, lo[j], hi[j], exact, cos_t, sin_t, tau, phi, G[j])
        for m in range(n):
            R[m * n_c + i] = F[m * n_c + i] + rj * phi[m]


@njit(**JIT_OPTIONS)
def _block_times(D, x, out):
    """out (n_x,) = 𝔇 x for the real block matrix 𝔇 of the complex D_k (H+1, n_c, n_c) in NLvib
    order: D_0 on the mean, [[Re, Im], [−Im, Re]] D_k on (cos k, sin k)."""
    H1 = D.shape[0]
    n_c = D.shape[1]
    for i in range(n_c):
        acc = 0.0
        for j in range(n_c):
            acc += D[0, i, j].real * x[j]
        out[i] = acc
    for k in range(1, H1):
        c = (2 * k - 1) * n_c
        s = 2 * k * n_c
        for i in range(n_c):
            acc_c = 0.0
            acc_s = 0.0
            for j in range(n_c):
                dr = D[k, i, j].real
                di = D[k, i, j].imag
                acc_c += dr * x[c + j] + di * x[s + j]
                acc_s += dr * x[s + j] - di * x[c + j]
            out[c + i] = acc_c
            out[s + i] = acc_s


@njit(**JIT_OPTIONS)
def _damped_residual(D, dD, x, load, dload, rows, lo, hi, rr, exact, cos_t, sin_t, tau, jacobian, R, Jx, Jp):
    """The damped MMS-HBM contact residual (:mod:`mmshbm.methods.mms.damped`) with F = 𝔇 x − load
    the force the structure needs, in place.

    D      : (H+1, n_c, n_c) complex D_k; dD : (n_p, H+1, n_c, n_c) their derivatives in the
             parameters (read if ``jacobian``)
    x      : (n_x,) NLvib-ordered coefficients of the massless DOFs, n_x = (2H+1) n_c
    load   : (n_x,) the condensed load; dload : (n_x, n_p) its derivatives
    rows, lo, hi, rr : per contact its massless DOF, interval and proximal parameter
    R      : (n_x,) <- F, and on contact rows F + r φ(x − F/r)
    Jx, Jp : (n_x, n_x), (n_x, n_p) <- ∂R/∂x, ∂R/∂params (if ``jacobian``)
    """
    n_c = D.shape[1]
    n = 2 * D.shape[0] - 1
    n_x = n * n_c
    n_p = dD.shape[0]
    n_k = rows.shape[0]
    _block_times(D, x, R)
    for a in range(n_x):
        R[a] -= load[a]
    F = R.copy()
    G = np.empty((n_k, n, n))
    _contact_rows(x, F, rows, n_c, lo, hi, rr, exact, cos_t, sin_t, tau, R, G)
    if not jacobian:
        return
    dF = np.empty(n_x)
    for p in range(n_p):
        _block_times(dD[p], x, dF)
        for a in range(n_x):
            Jp[a, p] = dF[a] - dload[a, p]
    for a in range(n_x):
        for b in range(n_x):
            Jx[a, b] = 0.0
    for i in range(n_c):
        for j in range(n_c):
            Jx[i, j] = D[0, i, j].real
    for k in range(1, D.shape[0]):
        c = (2 * k - 1) * n_c
        s = 2 * k * n_c
        for i in range(n_c):
            for j in range(n_c):
                dr = D[k, i, j].real
                di = D[k, i, j].imag
                Jx[c + i, c + j] = dr
                Jx[c + i, s + j] = di
                Jx[s + i, c + j] = -di
                Jx[s + i, s + j] = dr
    # contact rows: ∂R/∂x = (I − G) 𝔇 + r G on the DOF's own columns, ∂R/∂params = (I − G) ∂F
    dFi = np.empty((n, n_p))
    for jc in range(n_k):
        i = rows[jc]
        Gj = G[jc]
        for m in range(n):
            for p in range(n_p):
                dFi[m, p] = Jp[m * n_c + i, p]
        for m in range(n):
            row = m * n_c + i
            w0 = (1.0 if m == 0 else 0.0) - Gj[m, 0]
            for j in range(n_c):
                Jx[row, j] = w0 * D[0, i, j].real
            for k in range(1, D.shape[0]):
                c = 2 * k - 1
                s = 2 * k
                wc = (1.0 if m == c else 0.0) - Gj[m, c]
                ws = (1.0 if m == s else 0.0) - Gj[m, s]
                for j in range(n_c):
                    dr = D[k, i, j].real
                    di = D[k, i, j].imag
                    Jx[row, c * n_c + j] = wc * dr - ws * di
                    Jx[row, s * n_c + j] = wc * di + ws * dr
            for b in range(n):
                Jx[row, b * n_c + i] += rr[jc] * Gj[m, b]
            for p in range(n_p):
                v = 0.0
                for mm in range(n):
                    v += ((1.0 if mm == m else 0.0) - Gj[m, mm]) * dFi[mm, p]
                Jp[row, p] = v
