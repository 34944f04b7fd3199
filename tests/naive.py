"""Plain-loop, dense references for the finite-element matrices of the beam, and for the
harmonic projection of the contact law.

Nothing here imports :mod:`mmshbm.fe`: the element matrices are rebuilt from the
Timoshenko equations themselves (shape functions = exact static solution, integrated by
Gauss quadrature) and assembled with explicit Python loops into dense arrays, so that the
vectorised closed-form code can be asserted against them.

Conventions match :mod:`mmshbm.fe`: local DOFs ``[w1, θ1, w2, θ2]``, θ = dw/dx in the
Euler–Bernoulli limit, shear strain γ = dw/dx − θ, global order ``[w0, θ0, w1, θ1, ...]``.
"""

from __future__ import annotations

import numpy as np


def iie_coefficients(L: float, E: float, G: float, A: float, I: float, kappa: float) -> np.ndarray:
    """Polynomial coefficients of the interdependent-interpolation shape functions.

    The element's static homogeneous solution has w = a0 + a1 x + a2 x² + a3 x³ and
    θ = b0 + b1 x + b2 x². The Timoshenko equations without load,
    (κGA (w' − θ))' = 0 and E I θ'' + κGA (w' − θ) = 0, hold for every x when
    3 a3 = b2, 2 a2 = b1 and 2 E I b2 + κGA (a1 − b0) = 0; the four nodal values fix the
    rest. Returns C, shape (7, 4): column k holds (a0..a3, b0..b2) for unit nodal DOF k.
    """
    kGA = kappa * G * A
    S = np.zeros((7, 7))
    S[0, 3], S[0, 6] = 3.0, -1.0
    S[1, 2], S[1, 5] = 2.0, -1.0
    S[2, 1], S[2, 4], S[2, 6] = kGA, -kGA, 2.0 * E * I
    S[3, 0] = 1.0                                   # w(0)
    S[4, 4] = 1.0                                   # θ(0)
    S[5, :4] = [1.0, L, L**2, L**3]                 # w(L)
    S[6, 4:] = [1.0, L, L**2]                       # θ(L)
    rhs = np.zeros((7, 4))
    rhs[3:, :] = np.eye(4)
    return np.linalg.solve(S, rhs)


def iie_shape_functions(x, L, E, G, A, I, kappa):
    """w and θ shape functions and their x-derivatives at points ``x`` (m): four (m, 4) arrays."""
    C = iie_coefficients(L, E, G, A, I, kappa)
    x = np.asarray(x, dtype=float)
    P = np.stack([np.ones_like(x), x, x**2, x**3], axis=1)
    dP = np.stack([np.zeros_like(x), np.ones_like(x), 2 * x, 3 * x**2], axis=1)
    return P @ C[:4], P[:, :3] @ C[4:], dP @ C[:4], dP[:, :3] @ C[4:]


def element_by_quadrature(L, E, G, rho, A, I, kappa, n_gauss=6):
    """Dense (4, 4) stiffness and mass of one element by Gauss quadrature of

        K = ∫ E I θ'ᵀθ' + κGA γᵀγ dx,      M = ∫ ρA wᵀw + ρI θᵀθ dx

    with the shape functions of :func:`iie_shape_functions` (exact for degree <= 11)."""
    xg, wg = np.polynomial.legendre.leggauss(n_gauss)
    K = np.zeros((4, 4))
    M = np.zeros((4, 4))
    for xq, wq in zip(xg, wg, strict=True):
        x = np.array([(xq + 1.0) * L / 2.0])
        Nw, Nt, dNw, dNt = (a[0] for a in iie_shape_functions(x, L, E, G, A, I, kappa))
        gamma = dNw - Nt
        weight = wq * L / 2.0
        for i in range(4):
            for j in range(4):
                K[i, j] += weight * (E * I * dNt[i] * dNt[j] + kappa * G * A * gamma[i] * gamma[j])
                M[i, j] += weight * (rho * A * Nw[i] * Nw[j] + rho * I * Nt[i] * Nt[j])
    return K, M


def assemble_loop(element_matrices) -> np.ndarray:
    """Dense global matrix of a chain of 2-node elements, by explicit loops.

    ``element_matrices`` is a sequence of (4, 4) arrays, element ``e`` joining nodes e and
    e + 1; the result has shape (2 n_e + 2, 2 n_e + 2), order ``[w0, θ0, w1, θ1, ...]``."""
    n_e = len(element_matrices)
    A = np.zeros((2 * n_e + 2, 2 * n_e + 2))
    for e, Ae in enumerate(element_matrices):
        dofs = [2 * e, 2 * e + 1, 2 * e + 2, 2 * e + 3]
        for i in range(4):
            for j in range(4):
                A[dofs[i], dofs[j]] += Ae[i][j]
    return A


def beam_matrices(lengths, E, G, rho, A, I, kappa, clamped=True):
    """Dense (M, K) of a beam with the given element lengths, root first.

    Element matrices by :func:`element_by_quadrature`, assembled by :func:`assemble_loop`;
    ``clamped`` deletes the root's rows and columns ``w0, θ0``."""
    Ks, Ms = [], []
    for L in lengths:
        Ke, Me = element_by_quadrature(L, E, G, rho, A, I, kappa)
        Ks.append(Ke)
        Ms.append(Me)
    K, M = assemble_loop(Ks), assemble_loop(Ms)
    if clamped:
        K, M = K[2:, 2:], M[2:, 2:]
    return M, K


# ---------------------------------------------------------------------------------------
# Plain references for the harmonic transforms, the contact kernels and the condensation.
# DFT-matrix transforms, Python loops and dense solves: slow and obviously right.


def synthesis_matrix(H: int, N: int) -> np.ndarray:
    """E (N, 2H+1): x = E @ [c0, c1, s1, ..., cH, sH] at τ_j = 2πj/N."""
    tau = 2 * np.pi * np.arange(N) / N
    E = np.ones((N, 2 * H + 1))
    for k in range(1, H + 1):
        E[:, 2 * k - 1] = np.cos(k * tau)
        E[:, 2 * k] = np.sin(k * tau)
    return E


def projection(x: np.ndarray, H: int) -> np.ndarray:
    """Discrete Fourier projection of samples x (N,) on harmonics 0..H (NLvib order)."""
    N = len(x)
    E = synthesis_matrix(H, N)
    weights = np.full(2 * H + 1, 2.0 / N)
    weights[0] = 1.0 / N
    return weights * (E.T @ x)


def proximal_contact_loop(lam, g, r):
    """R = λ − max(0, λ − r g) and the active set, by a Python loop."""
    R = np.empty(len(lam))
    active = np.empty(len(lam))
    for j in range(len(lam)):
        R[j] = lam[j] - max(0.0, lam[j] - r * g[j])
        active[j] = 1.0 if lam[j] - r * g[j] > 0 else 0.0
    return R, active


def condensed_stiffness_dense(model, omega: float, H: int):
    """D_k and ∂D_k/∂Ω for k = 0..H by dense solves; shapes (H+1, n_c, n_c)."""
    b = model.blocks
    K, M = b["K_ll"].toarray(), b["M_ll"].toarray()
    K_lc, K_cc = b["K_lc"], b["K_cc"]
    D, dD = [], []
    for k in range(H + 1):
        Z = np.linalg.solve(K - (k * omega) ** 2 * M, K_lc)
        D.append(K_cc - K_lc.T @ Z)
        dD.append(-2 * k**2 * omega * Z.T @ M @ Z)
    return np.array(D), np.array(dD)


def mmshbm_full_residual(problem, A, B, omega, n_samples=None):
    """The MMS-HBM residual with the full (cosine and sine) Fourier ansatz, by DFT matrices
    and a Python loop over the samples: nothing of the production path is used but the
    condensed dynamic stiffness D_k(Ω).

    ``A``, ``B``: cosine and sine coefficients (H+1, n_c) of the massless DOFs (B[0] is
    ignored), Ω in rad/s. Returns the residual (2H+1, n_c) in NLvib order (c0, c1, s1, ...)
    and unscaled units (N): F_k at the massless DOFs without a stop, the projection of
    f + r((p − hi)₊ − (lo − p)₊), p = q − f/r, at each contact DOF, on ``n_samples``
    samples (default the problem's N; many samples approach the exact projection).
    """
    H, N = problem.H, (problem.N if n_samples is None else n_samples)
    D = problem.cond.dynamic_stiffness(omega, H, derivative=False)
    n_c = D.shape[1]
    Q = np.zeros((2 * H + 1, n_c))  # NLvib-ordered coefficients of q_c
    Q[0], Q[1::2], Q[2::2] = A[0], A[1:], B[1:]
    F = np.zeros_like(Q)
    F[0] = D[0] @ Q[0]
    for k in range(1, H + 1):
        F[2 * k - 1] = D[k] @ Q[2 * k - 1]
        F[2 * k] = D[k] @ Q[2 * k]
    E = synthesis_matrix(H, N)
    R = F.copy()
    for i, lo, hi, r in zip(problem.cdof, problem.lo, problem.hi, problem.r_each, strict=True):
        f, q = E @ F[:, i], E @ Q[:, i]
        R_t = np.empty(N)
        for j in range(N):
            p = q[j] - f[j] / r
            R_t[j] = f[j] + r * (max(0.0, p - hi) - max(0.0, lo - p))
        R[:, i] = projection(R_t, H)
    return R


def shift_coefficients(A, B, theta):
    """Cosine/sine coefficients (H+1, n) of x(τ + θ) from those of x(τ)."""
    k = np.arange(A.shape[0])[:, None]
    c, s = np.cos(k * theta), np.sin(k * theta)
    return A * c + B * s, -A * s + B * c


# ---------------------------------------------------------------------- contact projection
def product_matrix(C: np.ndarray, S: np.ndarray, H: int) -> np.ndarray:
    """G_ab = proj_a[s φ_b] in NLvib order (φ = 1, cos τ, sin τ, ..., cos Hτ, sin Hτ) from the
    spectrum (C, S) of s, by a Python double loop over the product formulas."""
    G = np.zeros((2 * H + 1, 2 * H + 1))
    for a in range(2 * H + 1):
        m, a_sin = (a + 1) // 2, a > 0 and a % 2 == 0
        w = 1.0 if a == 0 else 2.0
        for b in range(2 * H + 1):
            k, b_sin = (b + 1) // 2, b > 0 and b % 2 == 0
            d, t = abs(m - k), m + k
            if not a_sin and not b_sin:
                v = 0.5 * (C[d] + C[t])
            elif a_sin and b_sin:
                v = 0.5 * (C[d] - C[t])
            elif not a_sin:  # cos m · sin k = ½ (sin (k+m) + sin (k−m))
                v = 0.5 * (S[t] + np.sign(k - m) * S[d])
            else:  # sin m · cos k = ½ (sin (m+k) + sin (m−k))
                v = 0.5 * (S[t] + np.sign(m - k) * S[d])
            G[a, b] = w * v
    return G


def sampled_spectrum(g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sampled spectrum (C_n, S_n), n = 0..2H, of {g > 0} for samples g (N,) on τ_j = 2πj/N,
    with a dense DFT matrix; H = (N_coef − 1)//2 is taken from the caller's slicing."""
    N = g.shape[0]
    tau = 2 * np.pi * np.arange(N) / N
    n = np.arange(N)[:, None]
    s = (g > 0).astype(float)
    return (np.cos(n * tau) @ s) / N, (np.sin(n * tau) @ s) / N


def project_contact(p: np.ndarray, lo: float, hi: float, spectrum) -> tuple[np.ndarray, np.ndarray]:
    """Projection of (p − hi)₊ − (lo − p)₊ and its Jacobian for NLvib-ordered p (2H+1,),
    composed in NumPy from ``spectrum(c, s) -> (C, S)`` (n = 0..2H) and :func:`product_matrix`."""
    H = (p.shape[0] - 1) // 2
    c = np.concatenate([[p[0]], p[1::2]])
    s = np.concatenate([[0.0], p[2::2]])
    r = np.zeros(2 * H + 1)
    G = np.zeros((2 * H + 1, 2 * H + 1))
    for theta, sign in ((hi, 1.0), (lo, -1.0)):
        if np.isinf(theta):
            continue
        gc, gs = sign * c, sign * s
        gc[0] -= sign * theta
        C, S = spectrum(gc, gs)
        Gt = product_matrix(C, S, H)
        G += Gt
        indicator = np.zeros(2 * H + 1)
        indicator[0] = C[0]
        indicator[1::2] = 2 * C[1:H + 1]
        indicator[2::2] = 2 * S[1:H + 1]
        r += Gt @ p - theta * indicator
    return r, G
