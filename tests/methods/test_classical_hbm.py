"""r = "residual" is the classical harmonic balance of the masses, the node eliminated.

A massless contact node on a spring kc in front of a stop (gap g) sits at min(x, g)
while the mass it hangs on is at x, so the masses feel the bilinear force
kc·max(0, x − g): the chain is a piecewise-linear oscillator of its masses alone. The
classical harmonic balance of that oscillator (a truncated cosine series of every mass,
the Fourier coefficients of the bilinear force integrated exactly between the switching
instants) is written out below, independently of the package, and solved at the
frequency of an MMS-HBM point. Where every mode of the chain lies below the cut
(H+1)·ω₁, r = "residual" is the node's spring kc and MMS-HBM must give the same
coefficients to the solvers' tolerance: its truncation error is that of harmonic
balance itself. The static r (the default) is another Galerkin truncation of the same
law and must not.

Past the internal resonances of the two-mass chain several orbits of the family coexist
at one amplitude (one, two or three contact phases per period), and which of them the
backbone follows is the family search's choice. What holds for any of them is checked
against the exact event-driven orbits (:mod:`mmshbm.exact`): the backbone's orbit is a
truncation of the exact orbit shot from it, and the exact single-contact orbit is the
limit of exactly one of the orbits the branch lists, both judged by the orbit's re-solves
at 2H and 4H.
"""

import functools

import numpy as np
import pytest
from scipy.optimize import brentq, root

import mmshbm
from mmshbm import exact
from mmshbm.results.truncation import state_truncation_error


def chain(masses, springs, kc, gap=0.01):
    """Ground–m1–…–mn–node, spring i between mass i−1 (or ground) and mass i; the node on kc."""
    n = len(masses)
    K = np.zeros((n + 1, n + 1))
    K[0, 0] = springs[0]
    for i, s in enumerate(list(springs[1:]) + [kc]):
        K[np.ix_([i, i + 1], [i, i + 1])] += s * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return mmshbm.Model.from_matrices(np.diag(list(masses) + [0.0]), K, contact_dof=n, gap=gap, stop_side=1)


def _cos_cos(H: int, t: float) -> np.ndarray:
    """C[k, j] = ∫₀ᵗ cos(kτ) cos(jτ) dτ for k, j = 0..H, in closed form."""
    k = np.arange(H + 1)
    d, s = k[:, None] - k[None, :], k[:, None] + k[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        return 0.5 * (np.where(d == 0, t, np.sin(d * t) / d) + np.where(s == 0, t, np.sin(s * t) / s))


def bilinear_force_coefficients(a: np.ndarray, gap: float, kc: float) -> tuple[np.ndarray, np.ndarray]:
    """Cosine coefficients F_j (j = 0..H) of kc·max(0, x(τ) − gap) for the even signal
    x(τ) = Σ_k a_k cos kτ, and their Jacobian ∂F_j/∂a_k: the contact intervals in [0, π]
    from a fine sign scan refined by Brent's method, the integrals in closed form (the
    integrand vanishes at the interval ends, so the ends' motion adds nothing to the
    Jacobian)."""
    H = len(a) - 1
    orders = np.arange(H + 1)

    def x(tau):
        return float(a @ np.cos(orders * tau))

    grid = np.linspace(0.0, np.pi, 64 * (H + 1) + 1)
    v = np.cos(np.outer(grid, orders)) @ a - gap
    ends = [0.0] if v[0] > 0 else []
    for i in np.flatnonzero(v[:-1] * v[1:] < 0):
        ends.append(brentq(lambda t: x(t) - gap, grid[i], grid[i + 1], xtol=1e-15))
    if v[-1] > 0:
        ends.append(np.pi)
    D = np.zeros((H + 1, H + 1))  # ∫ over the contact intervals of cos kτ cos jτ
    for t0, t1 in zip(ends[::2], ends[1::2], strict=True):
        D += _cos_cos(H, t1) - _cos_cos(H, t0)
    J = (2.0 * kc / np.pi) * D  # even signal: (1/π)∫_{−π}^{π} = (2/π)∫_0^π; D is symmetric
    J[0] /= 2.0
    F = J @ a - gap * J[:, 0]
    return F, J


def classical_hbm(masses, springs, kc, gap, H, omega, start):
    """Cosine coefficients, shape (n, H+1), of the masses' classical harmonic balance at
    angular frequency ``omega`` (rad/s): (K_s − j²Ω²M) A_j + e_n F_j(A_n) = 0."""
    n = len(masses)
    Ks = np.zeros((n, n))
    Ks[0, 0] = springs[0]
    for i, s in enumerate(springs[1:]):
        Ks[np.ix_([i, i + 1], [i, i + 1])] += s * np.array([[1.0, -1.0], [-1.0, 1.0]])
    M = np.diag(masses)
    j = np.arange(H + 1)
    # the linear part, unknowns and equations ordered (mass, harmonic)
    L = np.zeros((n, H + 1, n, H + 1))
    for jj in j:
        L[:, jj, :, jj] = Ks - (jj * omega) ** 2 * M
    L = L.reshape(n * (H + 1), n * (H + 1))
    last = slice((n - 1) * (H + 1), n * (H + 1))  # the contact mass's harmonics

    def residual(z):
        F, _ = bilinear_force_coefficients(z[last], gap, kc)
        R = L @ z
        R[last] += F
        return R / kc

    def jacobian(z):
        _, JF = bilinear_force_coefficients(z[last], gap, kc)
        Jz = L.copy()
        Jz[last, last] += JF
        return Jz / kc

    sol = root(residual, start.ravel(), jac=jacobian, method="hybr", tol=1e-13)
    # the equations are forces over kc (m): solved to the round-off of the coefficients
    assert np.abs(residual(sol.x)).max() < 1e-13 * np.abs(start).max() * len(start.ravel()), sol.message
    return sol.x.reshape(n, H + 1)


def exact_orbit_of(branch, state, amplitude):
    """The exact symmetric orbit shot from the harmonic balance orbit ``state`` of ``branch``
    at ``amplitude``: Newton shooting from the masses' positions at its turning point
    farthest from the stop and its half period."""
    model = branch.get_model()
    n_samples = 8 * (branch.harmonics + 1)
    t, q = branch.solver.time_signals(state, n_samples=n_samples)
    i = int(np.argmax(-model.stop_side * q[model.contact_dof]))
    return exact.periodic_orbit(model, amplitude, guess=(q[model.l, i], 0.5 * n_samples * t[1]))


def _matches(branch, orbit, reference) -> bool:
    """Whether the harmonic balance ``orbit`` of ``branch`` is a truncation of the exact orbit
    ``reference``, judged by the re-solves of the orbit at 2H and 4H
    (:func:`~mmshbm.results.truncation.state_truncation_error`):

    - its frequency lies within twice its estimated truncation error of the exact one (the
      estimate extrapolates at the measured rate; the factor covers a rate still settling);
    - the 4H frequency lies within the last step |f(4H) − f(2H)| of the exact one: the
      remainder of a series contracting at a rate of at least 1 (the slowest measured on
      the test models), or oscillating with shrinking steps, is no larger than that step.

    A truncation of another orbit fails the second test by an order of magnitude: its 4H
    frequency converges elsewhere."""
    est = state_truncation_error(branch, reference.amplitude, orbit.frequency, orbit.state)
    f_exact, (_, f_2h, f_4h) = reference.frequency, est.frequency
    return bool(abs(orbit.frequency - f_exact) <= 2 * est.error * f_exact
                and abs(f_4h - f_exact) <= abs(f_4h - f_2h))


@functools.cache
def backbone_of(masses, springs, kc, r):
    """The chain's MMS-HBM backbone at H up to just past the tested amplitude."""
    model = chain(masses, springs, kc)
    branch = mmshbm.backbone(model, harmonics=H, max_amplitude=1.05 * AMPLITUDE * model.gap, r=r)
    assert branch.status == "bound:amplitude"
    return branch


def mms_point(branch, amplitude):
    """The backbone's angular frequency and the masses' cosine coefficients at ``amplitude``."""
    point = branch.solve_at([amplitude])
    n_samples = 4 * (H + 1)
    _, q = point.time_signals(0, n_samples=n_samples)
    c = np.fft.rfft(q[:-1], axis=1) / n_samples  # the masses (the node is the last DOF)
    assert np.abs(c[:, 1:H + 1].imag).max() < 1e-12 * np.abs(c).max()  # an even orbit
    coefficients = np.concatenate([c[:, :1].real, 2.0 * c[:, 1:H + 1].real], axis=1)
    return 2 * np.pi * point.frequency[0], coefficients


H = 31
AMPLITUDE = 1.3  # gaps
CASES = [
    # one mass, contact spring ~900 times the structure's: one orbit per amplitude
    pytest.param((2.0027,), (38.071,), 33749.83, id="one-mass"),
    # two masses, ω₂ = 12·ω₁ below the cut, the node's spring 20 times the stiffest: at 1.3
    # gaps orbits of one, two and three contact phases per period coexist on the family
    pytest.param((1.0, 0.2), (100.0, 2000.0), 4.0e4, id="two-mass"),
]


@pytest.mark.parametrize("masses, springs, kc", CASES)
def test_residual_r_is_the_classical_harmonic_balance(masses, springs, kc):
    branch = backbone_of(masses, springs, kc, "residual")
    model = branch.get_model()
    omegas = 2 * np.pi * model.linear_frequencies(len(masses))
    assert omegas[-1] < (H + 1) * omegas[0]  # every mode below the cut: r = kc
    amplitude = AMPLITUDE * model.gap
    omega, a_mms = mms_point(branch, amplitude)
    a_classical = classical_hbm(masses, springs, kc, model.gap, H, omega, a_mms)
    # both are solved to ~1e-10 relative residuals (Newton here, hybr in the test); the
    # Jacobian's conditioning near the fold-free backbone keeps the coefficients within
    # a few hundred times that
    np.testing.assert_allclose(a_mms, a_classical, rtol=0, atol=1e-8 * np.abs(a_classical).max())

    # the static r is another truncation: its point at the same amplitude is not the
    # classical solution at its frequency
    static = backbone_of(masses, springs, kc, None)
    omega_static, a_static = mms_point(static, amplitude)
    a_other = classical_hbm(masses, springs, kc, model.gap, H, omega_static, a_static)
    # measured 1.7e-2 (one mass), 2.1e-2 and 4.5e-2 (two masses, on the single- and the
    # two-contact orbit)
    assert np.abs(a_other - a_static).max() > 1e-3 * np.abs(a_static).max()


@pytest.mark.parametrize("masses, springs, kc", CASES)
def test_residual_r_orbits_are_truncations_of_exact_orbits(masses, springs, kc):
    """Whichever orbit the family search follows past the internal resonances, it is a
    truncation of an exact orbit, and the exact single-contact orbit has one truncation
    among the orbits the branch lists."""
    branch = backbone_of(masses, springs, kc, "residual")
    model = branch.get_model()
    amplitude = AMPLITUDE * model.gap
    orbits = branch.orbits_at(amplitude)
    backbone = orbits[0]
    assert backbone.source == "backbone"
    # (a) the backbone's orbit: the exact orbit shot from it is a genuine orbit of the
    # amplitude (farthest from the stop at t = 0), and the orbit its truncation
    shot = exact_orbit_of(branch, backbone.state, amplitude)
    assert shot.converged
    assert abs(shot.max_excursion / amplitude - 1) < 1e-9  # the refined sampled maximum: round-off
    assert _matches(branch, backbone, shot)

    # (b) the single-contact orbit (the shooting's default start, the one-DOF analogue):
    # exactly one listed orbit is its truncation
    single = exact.periodic_orbit(model, amplitude)
    assert single.converged and single.n_contacts == 1
    assert abs(single.max_excursion / amplitude - 1) < 1e-9
    assert sum(_matches(branch, orbit, single) for orbit in orbits) == 1

    if len(masses) == 1:
        # one orbit per amplitude: the static r's point is a truncation of the same orbit,
        # further from it (measured 9.0e-3 against 5.0e-4)
        static = backbone_of(masses, springs, kc, None)
        static_orbit = static.orbits_at(amplitude)[0]
        assert _matches(static, static_orbit, single)
        error, error_static = (abs(o.frequency / single.frequency - 1) for o in (backbone, static_orbit))
        assert error_static > 10 * error
