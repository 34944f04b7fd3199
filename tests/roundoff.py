"""Tolerances for two code paths that compute the same quantity in different floating-point
operations: a compiled loop against ``np.einsum``, ``ndarray.dot`` against ``@``, a residual
evaluated alone against the one evaluated with its Jacobian.

Two such paths agree in exact arithmetic and differ by their round-off only. A sum of n terms
t_i, computed in any order, with or without fused multiply-adds, in any blocking a BLAS kernel
picks, is within γ_n Σ|t_i| of the exact sum, γ_n = nε/(1 − nε) ≈ nε (Higham, "Accuracy and
Stability of Numerical Algorithms", 2nd ed., §3.1), and each product that forms a term adds
one rounding of its own. Two paths are therefore within

    2 (n + p) ε Σ|t_i|

of each other, p the number of roundings in each term's product. ``scale`` is Σ|t_i|, the
magnitude of the terms summed (not of the result, which may cancel to far below them: a
condensed stiffness, a residual at a converged point), ``terms`` is n + p; the tolerance
carries a factor ``ulps`` (4 by default: twice the bound's 2, for the rounding of the scale
itself and of a final scaling). Where the terms are not at hand, ``scale`` may bound them
(the norm of the inputs times the number of terms).

Equality to the last bit is asserted only where the same computation is repeated on the same
numbers (a save/load round trip, a resumed or repeated run, a kept copy, integer or boolean
data, values set exactly by construction); it is not a property of two different paths, which
round differently on another CPU, BLAS kernel or NumPy build.

A bug (a sign, a missing term, a wrong index) changes a result by the size of a term, i.e.
by about ε⁻¹/terms ≈ 10¹⁵/n times this tolerance.
"""

from __future__ import annotations

import numpy as np

EPS = np.finfo(float).eps


def roundoff_tolerance(scale, terms: int = 1, ulps: float = 4.0) -> np.ndarray:
    """Absolute tolerance ``ulps · terms · ε · scale`` between two paths of one computation
    (see the module docstring): ``scale`` the magnitude of the terms summed (a scalar or an
    array broadcasting against the result), ``terms`` the roundings of the longest chain (the
    number of terms summed plus those of each term's product)."""
    return ulps * max(int(terms), 1) * EPS * np.asarray(scale, dtype=float)


def assert_roundoff_close(actual, desired, scale, terms: int = 1, ulps: float = 4.0, err_msg: str = ""):
    """Assert |actual − desired| ≤ :func:`roundoff_tolerance` (scale, terms, ulps), entry by
    entry; NaNs must sit at the same places, infinities must be equal."""
    actual, desired = np.broadcast_arrays(np.asarray(actual, dtype=float), np.asarray(desired, dtype=float))
    tol = np.broadcast_to(roundoff_tolerance(scale, terms, ulps), actual.shape)
    np.testing.assert_array_equal(np.isnan(actual), np.isnan(desired), err_msg=f"NaNs differ {err_msg}")
    finite = np.isfinite(actual) & np.isfinite(desired)
    np.testing.assert_array_equal(np.where(finite, 0.0, actual), np.where(finite, 0.0, desired),
                                  err_msg=f"non-finite entries differ {err_msg}")
    err = np.where(finite, np.abs(actual - desired), 0.0)
    bad = err > tol
    if np.any(bad):
        worst = np.argmax(np.where(bad, err / np.maximum(tol, 1e-300), 0.0))
        i = tuple(int(j) for j in np.unravel_index(worst, bad.shape))
        magnitude = float(np.broadcast_to(scale, bad.shape)[i])
        raise AssertionError(f"{int(bad.sum())} of {bad.size} entries differ by more than round-off "
                             f"{err_msg}: at {i}, |{float(actual[i])!r} - {float(desired[i])!r}| = "
                             f"{err[i]:.3e} > {tol[i]:.3e} ({terms} terms of magnitude {magnitude:.3e})")


def product_scale(*factors) -> np.ndarray:
    """Σ|terms| of a product of matrices and vectors: the same product of their absolute
    values (``product_scale(A, x)`` is |A| |x|, the scale of each entry of A x)."""
    out = np.abs(np.asarray(factors[0], dtype=float))
    for f in factors[1:]:
        out = out @ np.abs(np.asarray(f, dtype=float))
    return out
