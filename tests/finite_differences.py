"""Finite-difference checks whose tolerance is their own measured error.

A central difference of step h has two errors: truncation, ~h² f‴/6, and round-off, ~σ/h,
where σ is the noise of one evaluation of f. σ is not ε·|f|: a condensed stiffness
D = K_cc − K_cl K_ll⁻¹ K_lc subtracts numbers 10⁴ times larger than itself, so its noise is ε
times the terms it cancels, and how those terms round depends on the BLAS kernel the machine
picks. A fixed relative tolerance is therefore right on one machine and wrong on the next.

Here both errors are measured at the point of the check:

* σ per entry from the difference table of f at nine points spaced h/4 apart (Moré & Wild,
  "Estimating computational noise", SIAM J. Sci. Comput. 33, 2011): the k-th difference of a
  smooth function is O(δᵏ), that of independent noise of variance σ² has variance C(2k, k) σ²;
* truncation from three steps, h, h/2 and h/4 (samples of the same table): two levels of
  Richardson extrapolation, whose difference bounds the truncation error while h is in the
  asymptotic range (see richardson_derivative).

The step starts at the caller's h and shrinks by 4 while the tolerance falls (a step too long
for the nearest resonance or switch). The check asserts
|analytic − value| ≤ safety · (truncation + round-off) + the analytic value's own round-off
(1e4·ε of the derivative's size, see assert_derivative), entry by entry, and refuses to pass
when that tolerance is too coarse to test anything (above ``rtol_cap`` of the derivative's
size): a kink or a switch inside the step shows up as "noise" and fails loudly instead of
widening the tolerance.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

EPS = np.finfo(float).eps


def _samples(f: Callable[[float], np.ndarray], h: float) -> np.ndarray:
    """f at s = i·h/4, i = −4 … 4, stacked along a new first axis."""
    return np.stack([np.asarray(f(i * h / 4)) for i in range(-4, 5)])


def noise_level(table: np.ndarray) -> np.ndarray:
    """Standard deviation of the evaluation noise, entry by entry, from equally spaced samples.

    ``table`` holds f at consecutive equally spaced points along its first axis. The estimate
    is the largest of the difference-table estimates of orders 4 to 6 (conservative where they
    differ). The spacing must be wide enough for f to change by several units in the last
    place between samples, or rounding repeats itself and looks like no noise at all; the
    check uses the finite difference's own samples (spacing h/4), whose smooth part adds
    about 0.12 (h/4)⁴ |f⁗| to the estimate.
    """
    estimates = []
    diff = table
    for k in range(1, 7):
        diff = np.diff(diff, axis=0)
        if k >= 4:
            gamma = float(np.prod(np.arange(1, k + 1))) ** 2 / float(np.prod(np.arange(1, 2 * k + 1)))
            estimates.append(np.sqrt(gamma * np.mean(np.abs(diff) ** 2, axis=0)))
    return np.max(estimates, axis=0)


def richardson_derivative(f: Callable[[float], np.ndarray], h: float) -> tuple[np.ndarray, np.ndarray]:
    """Derivative of f at s = 0 by two levels of Richardson extrapolation, and its error.

    Central differences D(h), D(h/2), D(h/4) (error series in h², h⁴, …) give the
    extrapolations R₁ = D(h/2) + (D(h/2) − D(h))/3 and R₂ = D(h/4) + (D(h/4) − D(h/2))/3
    (error O(h⁴)), and the value R₂ + (R₂ − R₁)/15. Returns (value, error), both of f's
    shape: error = |R₂ − R₁|/15 (the truncation error of R₂, a bound on the value's) plus
    4 σ/h, the standard deviation of the noise that the combination carries (the norm of its
    nine sample weights is 4.07/h).
    """
    table = _samples(f, h)
    d1 = (table[8] - table[0]) / (2 * h)
    d2 = (table[6] - table[2]) / h
    d4 = (table[5] - table[3]) / (h / 2)
    r1, r2 = d2 + (d2 - d1) / 3, d4 + (d4 - d2) / 3
    # nine samples estimate σ loosely, and rounding to the stored double is sparse noise
    # (most samples exact, a few one ulp off): never below one ulp of the values themselves
    sigma = np.maximum(noise_level(table), EPS * np.abs(table).max(axis=0))
    return r2 + (r2 - r1) / 15, np.abs(r2 - r1) / 15 + 4 * sigma / h


def _best_step(f, h, safety, floor, tries: int = 5):
    """The Richardson value and tolerance of the step, among h, h/4, h/16, …, whose largest
    tolerance is smallest: a step that is too long for the nearest singularity (a resonance
    of the condensed stiffness, a switch) shrinks until round-off takes over."""
    best = None
    for _ in range(tries):
        value, error = richardson_derivative(f, h)
        tol = safety * error + floor
        if best is not None and tol.max() >= best[1].max():
            break
        best = (value, tol)
        h /= 4
    return best


def assert_derivative(f: Callable[[float], np.ndarray], analytic, h: float, *, safety: float = 10.0,
                      rtol_cap: float = 1e-5, scale: float | None = None, name: str = "") -> None:
    """Assert that ``analytic`` is the derivative of f at s = 0 within the check's own error.

    f(s) is the function along the direction of the derivative (f(s) = F(x + s d) for a
    directional derivative J d); ``analytic`` has f's shape. ``scale`` is the size against
    which ``rtol_cap`` is measured (default: the largest |analytic| entry). The analytic
    value's own round-off is allowed as 1e4·ε·scale: the Jacobians checked here are sums
    over up to N·(2H+1) ≈ 10⁴ sample-harmonic products of the size of their largest entry.
    """
    analytic = np.asarray(analytic)
    scale = float(np.abs(analytic).max()) if scale is None else float(scale)
    value, tol = _best_step(f, h, safety, 1e4 * EPS * scale)
    if scale > 0:
        assert tol.max() <= rtol_cap * scale, (
            f"{name}: the finite difference cannot check this derivative: its error estimate "
            f"{tol.max():.3g} exceeds {rtol_cap:g} of the derivative's size {scale:.3g} "
            "(a switch or kink inside the step, or a step outside the asymptotic range)")
    miss = np.abs(analytic - value) - tol
    if (miss > 0).any():
        i = np.unravel_index(np.argmax(miss), miss.shape)
        raise AssertionError(
            f"{name}: entry {i}: analytic {analytic[i]!r}, finite difference {value[i]!r}, "
            f"difference {abs(analytic[i] - value[i]):.3g} > tolerance {tol[i]:.3g}")


def assert_jacobian(evaluate: Callable[[np.ndarray], np.ndarray], u: np.ndarray, J: np.ndarray,
                    h: float | np.ndarray, *, columns=None, directions=None, **options) -> None:
    """assert_derivative for each column of J (or for J·d along given directions).

    ``evaluate(u)`` returns the residual vector; ``h`` is the step (a scalar, or one per
    unknown for columns). ``columns`` selects unknowns (default: all); ``directions`` is an
    iterable of vectors d instead of columns. The tolerance cap is measured against the
    largest |J| entry, as a Jacobian's columns differ in size by orders of magnitude.
    """
    u = np.asarray(u, dtype=float)
    scale = options.pop("scale", float(np.abs(J).max()))
    if directions is None:
        cols = range(u.size) if columns is None else columns
        steps = np.broadcast_to(np.asarray(h, dtype=float), u.shape)
        for j in cols:
            e = np.zeros_like(u)
            e[j] = 1.0
            assert_derivative(lambda s, e=e: evaluate(u + s * e), J[:, j], float(steps[j]),
                              scale=scale, name=f"column {j}", **options)
    else:
        for n, d in enumerate(directions):
            d = np.asarray(d, dtype=float)
            assert_derivative(lambda s, d=d: evaluate(u + s * d), J @ d, float(h),
                              scale=scale, name=f"direction {n}", **options)
