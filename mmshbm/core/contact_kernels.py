"""Harmonic projections of the proximal contact law, sampled or exact (C¹), and the fused
MMS-HBM residual built on them.

Contact law per DOF. A contact DOF with admissible positions [lo, hi]
(:func:`~mmshbm.model.contact.admissible_intervals`; ±inf without a stop on a side), the
force f(τ) the structure needs there and its displacement q(τ) satisfy the Signorini
law exactly when, for any r > 0 and p = q − f/r,

    R(τ) = f + r [(p − hi)₊ − (lo − p)₊] = 0.

(At the upper stop the structure needs f = −λ ≤ 0 and q = hi; in between f = 0.) With
the indicator s(τ) of the active set {p > hi} ∪ {p < lo}, R = f + r s (p − θ), θ = hi or
lo, and the harmonic projection of s·p is a matrix times the coefficients of p:

    proj_m[s · cos kτ] = G_mk = ε_m/2 (C_|m−k| + C_m+k),   C_n = (1/2π) ∫_{s=1} cos nτ dτ,

ε_0 = 1, ε_m = 2 (and the analogous sine terms for a general trigonometric polynomial).
Only the spectrum C_n (n = 0..2H) of the active set depends on how the projection is done:

* **sampled** (AFT): C_n = (1/N) Σ_j s(τ_j) cos nτ_j on N samples; a sample changing its
  active set is a kink of the residual.
* **exact** (C¹): the zeros of the trigonometric polynomial p − θ are bracketed on the N
  samples, refined by safeguarded Newton to round-off, and C_n is integrated in closed
  form over the arcs; s·(p − θ) vanishes at the moving arc ends, so the same G is the
  exact Jacobian (docs/design.md §2, §8).

The kernels take plain arrays and know nothing of models. Numba's cache keys a kernel on
its own file only: after editing a kernel here, the cached callers in other files
(``corrector_kernels``) are stale until their file changes or the cache is cleared
(``find mmshbm -name '*.nb[ic]' -delete``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .kernels import JIT_OPTIONS

__all__: list[str] = []  # kernels only; the projections as functions: mmshbm.core.projection

_TWO_PI = 2.0 * math.pi


# ---------------------------------------------------------------------- trigonometric polynomials
@njit(**JIT_OPTIONS)
def _trig_eval(c, s, tau):
    """g(τ), g′(τ), g″(τ) of g = c_0 + Σ_k (c_k cos kτ + s_k sin kτ); c, s shape (H+1,)."""
    H = c.shape[0] - 1
    c1 = math.cos(tau)
    s1 = math.sin(tau)
    ck = 1.0
    sk = 0.0
    g = c[0]
    g1 = 0.0
    g2 = 0.0
    for k in range(1, H + 1):
        ck, sk = ck * c1 - sk * s1, sk * c1 + ck * s1
        a = c[k] * ck + s[k] * sk
        b = -c[k] * sk + s[k] * ck
        g += a
        g1 += k * b
        g2 -= k * k * a
    return g, g1, g2


@njit(**JIT_OPTIONS)
def _refine(c, s, a, b, fa, order):
    """Zero of g (order 0) or of g′ (order 1) in the bracket [a, b], where the function has
    the sign of ``fa`` at a and the opposite sign at b: safeguarded Newton (bisection
    whenever a step leaves the bracket), to round-off in τ: it stops where the function
    value is below the round-off of its evaluation (Newton's steps there only hop between
    neighbouring doubles; an end of the bracket with such a value is the zero), or where
    the step or the bracket is at round-off in τ."""
    H = c.shape[0] - 1
    noise = abs(c[0]) if order == 0 else 0.0
    for k in range(1, H + 1):
        noise += (abs(c[k]) + abs(s[k])) * (1.0 if order == 0 else k)
    noise *= 8e-16
    if abs(fa) <= noise:  # a zero on a sample: Newton would bisect towards it to round-off
        return a
    gb, gb1, _ = _trig_eval(c, s, b)
    if abs(gb if order == 0 else gb1) <= noise:
        return b
    x = 0.5 * (a + b)
    for _ in range(100):
        g, g1, g2 = _trig_eval(c, s, x)
        f = g if order == 0 else g1
        df = g1 if order == 0 else g2
        if abs(f) <= noise:
            return x
        if (f > 0.0) == (fa > 0.0):
            a = x
        else:
            b = x
        step_ok = df != 0.0
        xn = x - f / df if step_ok else 0.5 * (a + b)
        if not (a < xn < b):
            xn = 0.5 * (a + b)
        if abs(xn - x) <= 2e-16 * (1.0 + abs(x)) or b - a <= 4e-16 * (1.0 + abs(a)):
            return xn
        x = xn
    return x


@njit(**JIT_OPTIONS)
def _zeros(c, s, g_t, dg_t, tau_t, roots):
    """Zeros of g on [0, 2π), bracketed on the samples g_t = g(τ_j), dg_t = g′(τ_j) at
    τ_j = tau_t[j] (equispaced, τ_0 = 0); returns their count (stored sorted in ``roots``)."""
    N = g_t.shape[0]
    n = 0
    # the order as run-time integers: literal arguments would compile _refine twice
    root, extremum = np.int64(0), np.int64(1)
    # |g″| <= M2 everywhere, so between two samples of one sign g stays beyond
    # min(|g_a|, |g_b|) − M2 h²/8: a hidden pair of zeros needs a sample within that margin
    m2 = 0.0
    for k in range(1, c.shape[0]):
        m2 += k * k * (abs(c[k]) + abs(s[k]))
    h = _TWO_PI / N
    margin = 1.01 * m2 * h * h / 8.0 + 1e-300
    for j in range(N):
        jn = j + 1 if j + 1 < N else 0
        a = tau_t[j]
        b = tau_t[jn] if jn > 0 else _TWO_PI
        ga = g_t[j]
        gb = g_t[jn]
        if ga == 0.0:
            if n < roots.shape[0]:
                roots[n] = a
                n += 1
            continue
        if (ga > 0.0) != (gb > 0.0):
            if gb == 0.0:
                continue  # the next interval records it
            if n < roots.shape[0]:
                roots[n] = _refine(c, s, a, b, ga, root)
                n += 1
        elif dg_t[j] * dg_t[jn] < 0.0 and min(abs(ga), abs(gb)) <= margin:
            # an extremum inside: a pair of close zeros hides if it lies on the other side
            t_ext = _refine(c, s, a, b, dg_t[j], extremum)
            g_ext, _, _ = _trig_eval(c, s, t_ext)
            if g_ext != 0.0 and (g_ext > 0.0) != (ga > 0.0) and n + 1 < roots.shape[0]:
                roots[n] = _refine(c, s, a, t_ext, ga, root)
                roots[n + 1] = _refine(c, s, t_ext, b, g_ext, root)
                n += 2
    return n


@njit(**JIT_OPTIONS)
def _arc_spectrum(c, s, g_t, dg_t, tau_t, roots, C, S):
    """Exact spectrum of the indicator of {g > 0}: C_n = (1/2π)∫ cos nτ, S_n = (1/2π)∫ sin nτ
    over that set, n = 0..len(C)−1 (in place)."""
    n_spec = C.shape[0]
    for p in range(n_spec):
        C[p] = 0.0
        S[p] = 0.0
    nr = _zeros(c, s, g_t, dg_t, tau_t, roots)
    if nr == 0:
        if g_t[0] > 0.0:
            C[0] = 1.0
        return
    for i in range(nr):
        a = roots[i]
        b = roots[i + 1] if i + 1 < nr else roots[0] + _TWO_PI
        if b <= a:
            continue
        g_mid, _, _ = _trig_eval(c, s, 0.5 * (a + b))
        if g_mid <= 0.0:
            continue
        C[0] += b - a
        ca, sa = math.cos(a), math.sin(a)
        cb, sb = math.cos(b), math.sin(b)
        cna, sna, cnb, snb = 1.0, 0.0, 1.0, 0.0
        for p in range(1, n_spec):
            cna, sna = cna * ca - sna * sa, sna * ca + cna * sa
            cnb, snb = cnb * cb - snb * sb, snb * cb + cnb * sb
            C[p] += (snb - sna) / p
            S[p] += (cna - cnb) / p
    for p in range(n_spec):
        C[p] /= _TWO_PI
        S[p] /= _TWO_PI


@njit(**JIT_OPTIONS)
def _sampled_spectrum(g_t, cos_table, sin_table, C, S):
    """Sampled spectrum of the indicator of {g > 0}: C_n = (1/N) Σ_j s_j cos nτ_j (and S_n
    with sines; sin_table may have fewer rows, the rest of S is zero)."""
    N = g_t.shape[0]
    for p in range(C.shape[0]):
        acc = 0.0
        acc_s = 0.0
        for j in range(N):
            if g_t[j] > 0.0:
                acc += cos_table[p, j]
                if p < sin_table.shape[0]:
                    acc_s += sin_table[p, j]
        C[p] = acc / N
        S[p] = acc_s / N


@njit(**JIT_OPTIONS)
def _spectrum(c, s, cos_table, sin_table, tau_t, exact, g_t, dg_t, roots, C, S):
    """Spectrum of {g > 0} for g with coefficients (c, s) of degree H = len(c) − 1: samples
    g_t (and g′ for the exact route) from the tables, then the sampled or exact spectrum."""
    N = g_t.shape[0]
    H = c.shape[0] - 1
    # harmonic by harmonic along the table rows (contiguous), each sample summed in k order
    for j in range(N):
        g_t[j] = c[0]
        dg_t[j] = 0.0
    for k in range(1, H + 1):
        ck = c[k]
        sk = s[k]
        for j in range(N):
            g_t[j] += ck * cos_table[k, j] + sk * sin_table[k, j]
            dg_t[j] += k * (sk * cos_table[k, j] - ck * sin_table[k, j])
    if exact:
        _arc_spectrum(c, s, g_t, dg_t, tau_t, roots, C, S)
    else:
        _sampled_spectrum(g_t, cos_table, sin_table, C, S)


# ---------------------------------------------------------------------- fused MMS-HBM
@njit(**JIT_OPTIONS)
def _mmshbm_eval(D, dD, a, eta, omega, pole_k, pole_b, pole_w2, cdof, lo, hi, r, exact, cos_table, sin_table,
                 tau_t, rowscale, colscale, jacobian, R, J, F, dF, pc, ps, gc, g_t, dg_t, roots, C_hi, C_lo,
                 S_w, P):
    """Scaled cosine-only MMS-HBM residual (and Jacobian) for any number of contact DOFs,
    with the poles of D_k carried by extra unknowns η (:mod:`mmshbm.core.poles`).

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
def _series_peak(c, s, cos_table, sin_table, y):
    """Largest value of g = c_0 + Σ_k (c_k cos kτ + s_k sin kτ) over the period: the largest of
    the samples ``y`` (= g on the table's grid, filled here), refined by safeguarded Newton
    on g′ = 0 between its neighbours (to round-off)."""
    N = y.shape[0]
    H = c.shape[0] - 1
    j = 0
    for i in range(N):
        v = c[0]
        for k in range(1, H + 1):
            v += c[k] * cos_table[k, i] + s[k] * sin_table[k, i]
        y[i] = v
        if v > y[j]:
            j = i
    best = y[j]
    h = _TWO_PI / N
    lo = (j - 1) * h
    hi = (j + 1) * h
    tau = j * h
    for _ in range(12):
        g, g1, g2 = _trig_eval(c, s, tau)
        if g > best:
            best = g
        if g2 >= 0.0:
            break
        step = g1 / g2
        tau_new = tau - step
        if tau_new <= lo or tau_new >= hi:
            break
        tau = tau_new
        if abs(step) <= 1e-15:
            g, g1, g2 = _trig_eval(c, s, tau)
            if g > best:
                best = g
            break
    return best


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
