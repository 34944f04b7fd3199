"""Numba kernel of penalty harmonic balance on the condensed contact DOFs
(:mod:`mmshbm.methods.penalty.reduced`).

One kernel, no callees in other files (numba's on-disk cache does not see edits to a callee
elsewhere); it shares :data:`~mmshbm.harmonic.kernels.JIT_OPTIONS`.
"""

from __future__ import annotations

from numba import njit

from ...harmonic.kernels import JIT_OPTIONS

__all__: list[str] = []


@njit(**JIT_OPTIONS)
def _penalty_reduced_residual(D, dD, a, ci, lo, hi, kp, C, rowscale, colscale, jacobian, R, J, q, s, P):
    """Scaled residual and Jacobian of cosine-only penalty HBM on condensed DOFs, in place.

        R_k = D_k a_k + Σ_i e_{ci_i} proj_k f_i(q_i(τ)),
        f_i(q) = kp (max(0, q − hi_i) − max(0, lo_i − q))     (the penalty springs' force),

    with q_i(τ) = Σ_k a[k, ci_i] cos kτ sampled at τ_j = 2πj/N and proj_k the cosine
    projection. The Jacobian adds kp·P^(i) (cosine product matrix of the active set
    [q > hi] + [q < lo]) in the rows and columns of contact DOF i, and ∂D_k/∂Ω a_k in the
    Ω column.

    D, dD : (H+1, n_c, n_c); a : (H+1, n_c) (m); ci : (n_i,) int64 positions of the contact
    DOFs in a; lo, hi : (n_i,) admissible intervals (m, ±inf without a stop); kp : N/m;
    C : (H+1, N) cos kτ_j; rowscale ((H+1) n_c,), colscale ((H+1) n_c + 1,);
    R : ((H+1) n_c,) and J ((H+1) n_c, (H+1) n_c + 1) outputs, scaled (J only if
    ``jacobian``); q, s : (N,), P : (H+1, H+1) work arrays.
    """
    H1, n_c = a.shape
    N = C.shape[1]
    for k in range(H1):
        for r in range(n_c):
            acc = 0.0
            for c in range(n_c):
                acc += D[k, r, c] * a[k, c]
            R[k * n_c + r] = acc
    if jacobian:
        for r in range(J.shape[0]):
            for c in range(J.shape[1]):
                J[r, c] = 0.0
        for k in range(H1):
            for r in range(n_c):
                acc = 0.0
                for c in range(n_c):
                    J[k * n_c + r, k * n_c + c] = D[k, r, c]
                    acc += dD[k, r, c] * a[k, c]
                J[k * n_c + r, H1 * n_c] = acc
    for i in range(ci.shape[0]):
        d = ci[i]
        for j in range(N):
            x = 0.0
            for k in range(H1):
                x += a[k, d] * C[k, j]
            f = 0.0
            act = 0.0
            if x > hi[i]:
                f = kp * (x - hi[i])
                act = 1.0
            elif x < lo[i]:
                f = kp * (x - lo[i])
                act = 1.0
            q[j] = f
            s[j] = act
        for k in range(H1):
            acc = 0.0
            for j in range(N):
                acc += q[j] * C[k, j]
            R[k * n_c + d] += acc * ((1.0 if k == 0 else 2.0) / N)
        if jacobian:
            for m in range(H1):
                cm = (1.0 if m == 0 else 2.0) / N
                for k in range(m, H1):
                    acc = 0.0
                    for j in range(N):
                        acc += s[j] * C[m, j] * C[k, j]
                    P[m, k] = acc
                for k in range(H1):
                    v = P[m, k] if k >= m else P[k, m]
                    J[m * n_c + d, k * n_c + d] += kp * cm * v
    for r in range(R.shape[0]):
        R[r] /= rowscale[r]
    if jacobian:
        for r in range(J.shape[0]):
            for c in range(J.shape[1]):
                J[r, c] *= colscale[c] / rowscale[r]
