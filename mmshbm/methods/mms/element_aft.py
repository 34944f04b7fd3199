"""The force of a model's elements on a set of DOFs by alternating frequency–time (AFT).

The DOFs of the set move as truncated Fourier series in τ = Ωt; their samples at
τ_j = 2πj/N give each element's relative displacement, its law gives the force and its
derivative at every sample (:meth:`mmshbm.elements.Element.sampled`), and the discrete
Fourier projection gives the force's coefficients and their exact derivatives with
respect to the displacement coefficients,

    q(τ_j) = Σ_b E_jb X_b,    F_b = Σ_j P_bj f(q(τ_j)),    ∂F_b/∂X_c = Σ_j P_bj f'(q(τ_j)) E_jc,

with E the synthesis matrix of the basis (cosine-only: cos kτ, k = 0..H; full: 1, cos τ,
sin τ, ..., cos Hτ, sin Hτ, NLvib's order) and P its discrete projection. For a
polynomial law of degree d the projection is exact when N >= (d + 1) H + 1; a law with
kinks (a compliant stop) converges in N. The elements are displacement laws, so nothing
here depends on Ω.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ElementForces", "aliasing_free_samples"]


def aliasing_free_samples(elements, harmonics: int) -> int | None:
    """(d + 1) H + 1 for the largest polynomial degree d of ``elements``; None when an
    element has kinks (no finite N is exact)."""
    degrees = [e.degree for e in elements]
    if any(d is None for d in degrees):
        return None
    return (max(degrees) + 1) * harmonics + 1


class ElementForces:
    """The coefficients of the elements' forces on the DOFs ``dofs`` and their Jacobian.

    Parameters
    ----------
    elements : sequence of Element
        Each acts on DOFs among ``dofs``.
    dofs : ndarray of int, shape (n_s,)
        The DOFs whose coefficients are the unknowns (the columns of X).
    harmonics, n_samples : int
        H and N >= 2H + 1.
    cosine_only : bool
        The basis: cos kτ (k = 0..H, H+1 functions) or the full one (2H+1).
    """

    def __init__(self, elements, dofs, harmonics: int, n_samples: int, cosine_only: bool):
        self.elements = tuple(elements)
        position = {int(d): i for i, d in enumerate(dofs)}
        self.positions = [np.array([position[d] for d in e.dofs], dtype=int) for e in self.elements]
        H, N = int(harmonics), int(n_samples)
        tau = 2 * np.pi * np.arange(N) / N
        k = np.arange(H + 1)
        if cosine_only:
            E = np.cos(np.outer(tau, k))
            weight = np.where(k == 0, 1.0, 2.0) / N
            P = weight[:, None] * E.T
        else:
            E = np.empty((N, 2 * H + 1))
            E[:, 0] = 1.0
            E[:, 1::2] = np.cos(np.outer(tau, k[1:]))
            E[:, 2::2] = np.sin(np.outer(tau, k[1:]))
            weight = np.full(2 * H + 1, 2.0 / N)
            weight[0] = 1.0 / N
            P = weight[:, None] * E.T
        #: synthesis (N, n_b) and projection (n_b, N) matrices
        self.E, self.P = E, P
        self.n_basis = E.shape[1]
        self.n_dofs = len(dofs)

    def samples(self, X: np.ndarray) -> np.ndarray:
        """q(τ_j) (N, n_s) of the coefficients X (n_b, n_s)."""
        return self.E @ X

    def evaluate(self, X: np.ndarray, jacobian: bool = True):
        """(F, J): the force coefficients F (n_b, n_s) (N) of the coefficients X (n_b, n_s),
        and with ``jacobian`` ∂F/∂X as J (n_b, n_s, n_b, n_s) (row (b, i), column (c, j):
        the layout of ``F.ravel()`` and ``X.ravel()``), else None."""
        X = np.asarray(X, dtype=float)
        q = self.E @ X
        F = np.zeros((self.n_basis, self.n_dofs))
        J = np.zeros((self.n_basis, self.n_dofs, self.n_basis, self.n_dofs)) if jacobian else None
        for element, pos in zip(self.elements, self.positions, strict=True):
            f, df = element.sampled(q[:, pos].T)
            F[:, pos] += self.P @ f.T
            if jacobian:
                for a, i in enumerate(pos):
                    for b, j in enumerate(pos):
                        J[:, i, :, j] += (self.P * df[a, b][None, :]) @ self.E
        return F, J

    def potential(self, q: np.ndarray) -> float:
        """Σ V(δ) (J) of the elements at one configuration ``q`` (n_s,) of the set's DOFs."""
        q = np.asarray(q, dtype=float)
        return float(sum(np.sum(e.potential(e.relative(q[pos][:, None]))) for e, pos in
                         zip(self.elements, self.positions, strict=True)))

    def mean_potential(self, X: np.ndarray) -> float:
        """The period mean of Σ V(δ) (J) on the N samples of the coefficients X (n_b, n_s)."""
        q = self.E @ np.asarray(X, dtype=float)
        total = 0.0
        for e, pos in zip(self.elements, self.positions, strict=True):
            total += float(np.mean(e.potential(e.relative(q[:, pos].T))))
        return total


def series_peak(coefficients: np.ndarray, sign: float = 0.0, n_fine: int = 1024) -> float:
    """The largest value of sign·x(τ) (sign 0: of |x(τ)|) over the period of the series
    with NLvib-ordered ``coefficients`` (2H+1,): located on ``n_fine`` samples and refined
    by Newton on x'(τ) (to round-off in τ)."""
    c = np.asarray(coefficients, dtype=float)
    H = (len(c) - 1) // 2
    k = np.arange(1, H + 1)
    cos_c, sin_c = c[1::2], c[2::2]

    def value(t):
        return c[0] + cos_c @ np.cos(k * t) + sin_c @ np.sin(k * t)

    tau = 2 * np.pi * np.arange(n_fine) / n_fine
    x = c[0] + np.cos(np.outer(tau, k)) @ cos_c + np.sin(np.outer(tau, k)) @ sin_c
    candidates = [int(np.argmax(x)), int(np.argmin(x))] if sign == 0 else [int(np.argmax(sign * x))]
    best = -np.inf
    for j in candidates:
        t = tau[j]
        s = (1.0 if x[j] >= 0 else -1.0) if sign == 0 else sign
        for _ in range(20):  # Newton on x'(τ) = 0 from the best sample, kept within one sample step
            d1 = -(k * cos_c) @ np.sin(k * t) + (k * sin_c) @ np.cos(k * t)
            d2 = -(k * k * cos_c) @ np.cos(k * t) - (k * k * sin_c) @ np.sin(k * t)
            if d2 == 0:
                break
            step = -d1 / d2
            if abs(step) > 2 * np.pi / n_fine:
                break
            t += step
            if abs(step) < 1e-15:
                break
        peak = max(s * value(t), s * x[j])
        best = max(best, peak)
    return float(best)
