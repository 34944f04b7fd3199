"""The Timoshenko beam finite elements against independent ground truth.

Ground truth used here (none of it comes from :mod:`mmshbm.fe`):

* the element rebuilt from the Timoshenko equations and integrated by quadrature
  (``tests/naive.py``), assembled by plain loops;
* rigid-body motions, and the exact static deflection of an end-loaded cantilever,
  w(x) = P/(EI) (L x²/2 − x³/6) + P x/(κGA), which the IIE must reproduce at the nodes
  for any mesh and any slenderness (no shear locking);
* the Euler–Bernoulli clamped-free roots β_n L;
* the continuum Timoshenko clamped-free frequency equation (shear and rotary inertia),
  solved below the second spectrum with ``brentq``.
"""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
import scipy.linalg as la
from naive import beam_matrices, element_by_quadrature, iie_shape_functions
from scipy.optimize import brentq

import mmshbm
from mmshbm.fe import TimoshenkoBeam, assembly, default_beam, element, mesh

BETA_L = np.array([1.8751040687119611, 4.6940911329741745, 7.8547574382376126, 10.995540734875467])

SLENDER = TimoshenkoBeam(length=1.0, width=0.01, height=1e-4, E=210e9, rho=7850.0)  # h/L = 1e-4
STUBBY = TimoshenkoBeam(length=0.5, width=0.02, height=0.1, E=210e9, rho=7850.0)  # L/h = 5


# ---------------------------------------------------------------------------- continuum
def _timoshenko_det(omega: float, beam: TimoshenkoBeam) -> float:
    """Frequency determinant of the clamped-free Timoshenko beam below the second spectrum.

    W'' − Θ' = −(ρω²/κG) W and E I Θ'' + κGA (W' − Θ) = −ρIω² Θ have solutions e^{sx} with
    s⁴ + ω²(ρ/E + ρ/κG) s² + (ρAω²/EI)(ρIω²/κGA − 1) = 0. Below the cut-off
    ω_c = √(κGA/ρI) the roots are s = ±α and ±iβ, so
    W = A1 cosh αx + A2 sinh αx + A3 cos βx + A4 sin βx and
    Θ = k_α (A1 sinh αx + A2 cosh αx) + k_β (A3 sin βx − A4 cos βx) with
    k_α = (κGα² + ρω²)/(κGα), k_β = (ρω² − κGβ²)/(κGβ).
    Conditions: W(0) = Θ(0) = 0 (clamped), Θ'(L) = 0 (no moment), W'(L) − Θ(L) = 0 (no shear).
    """
    s = beam.section()
    E, rho, A, I = s["E"], s["rho"], s["A"], s["I"]
    kG = s["kappa"] * s["G"]
    L = beam.length
    w2 = omega**2
    b = w2 * (rho / E + rho / kG)
    c = (rho * A * w2 / (E * I)) * (rho * I * w2 / (kG * A) - 1.0)
    assert c < 0.0, "above the second spectrum"
    disc = np.sqrt(b * b - 4.0 * c)
    alpha = np.sqrt((disc - b) / 2.0)
    beta = np.sqrt((disc + b) / 2.0)
    ka = (kG * alpha**2 + rho * w2) / (kG * alpha)
    kb = (rho * w2 - kG * beta**2) / (kG * beta)
    ch, sh = np.cosh(alpha * L), np.sinh(alpha * L)
    co, si = np.cos(beta * L), np.sin(beta * L)
    D = np.array([
        [1.0, 0.0, 1.0, 0.0],
        [0.0, ka, 0.0, -kb],
        [ka * alpha * ch, ka * alpha * sh, kb * beta * co, kb * beta * si],
        [(alpha - ka) * sh, (alpha - ka) * ch, -(beta + kb) * si, (beta + kb) * co],
    ])
    D /= np.abs(D).max(axis=1, keepdims=True)  # positive row scaling: same sign, same zeros
    return float(np.linalg.det(D))


@functools.cache
def continuum_frequencies(beam: TimoshenkoBeam, n: int) -> np.ndarray:
    """The ``n`` lowest clamped-free Timoshenko frequencies (Hz) by sign scan + brentq."""
    s = beam.section()
    omega_c = np.sqrt(s["kappa"] * s["G"] * s["A"] / (s["rho"] * s["I"]))
    omega_eb = 2 * np.pi * beam.euler_bernoulli_frequencies(n + 1)
    top = min((1 - 1e-9) * omega_c, omega_eb[-1])  # Timoshenko lies below Euler-Bernoulli
    grid = np.linspace(0.2 * omega_eb[0], top, 3000)
    d = np.array([_timoshenko_det(w, beam) for w in grid])
    idx = np.flatnonzero(np.sign(d[:-1]) != np.sign(d[1:]))
    assert len(idx) >= n, "not enough roots below the second spectrum"
    roots = [brentq(_timoshenko_det, grid[i], grid[i + 1], args=(beam,), xtol=1e-13 * grid[i],
                    rtol=1e-15) for i in idx[:n]]
    return np.array(roots) / (2 * np.pi)


def beta_l(beam: TimoshenkoBeam, f_hz) -> np.ndarray:
    """β L = L (ω² ρA / EI)^(1/4) from frequencies in Hz."""
    omega = 2 * np.pi * np.asarray(f_hz)
    return beam.length * (omega**2 * beam.rho * beam.area / (beam.E * beam.inertia)) ** 0.25


def test_continuum_solver_has_the_euler_bernoulli_limit():
    # validates the ground truth itself: shear and rotary inertia vanish as h/L -> 0
    assert np.allclose(beta_l(SLENDER, continuum_frequencies(SLENDER, 3)), BETA_L[:3], rtol=1e-6, atol=0)
    # and lower a stubby beam's frequencies, the more the higher the mode
    ratio = continuum_frequencies(STUBBY, 3) / STUBBY.euler_bernoulli_frequencies(3)
    assert np.all(ratio < 1) and np.all(np.diff(ratio) < 0)


# ---------------------------------------------------------------------------- element
SECTION = {"E": 210e9, "G": 80e9, "rho": 7850.0, "A": 2.7e-4, "I": 4.1e-9, "kappa": 5 / 6}
LENGTHS = np.array([1e-3, 0.02, 0.1, 1.0])  # Φ from ~130 down to ~1e-4


def test_element_matches_quadrature_of_exact_static_shape_functions():
    K, M = element.element_matrices(LENGTHS, **SECTION)
    assert K.shape == M.shape == (len(LENGTHS), 4, 4)
    for e, L in enumerate(LENGTHS):
        Kq, Mq = element_by_quadrature(L, **SECTION)
        assert np.allclose(K[e], Kq, rtol=0, atol=1e-12 * np.abs(Kq).max())
        assert np.allclose(M[e], Mq, rtol=0, atol=1e-12 * np.abs(Mq).max())


def test_shape_functions_match_the_static_solution():
    xi = np.linspace(0, 1, 11)
    s = SECTION
    for L in LENGTHS:
        phi = element.shear_parameter(L, s["E"], s["G"], s["A"], s["I"], s["kappa"])
        N_w, N_t = element.shape_functions(xi, L, phi)
        Nw, Nt, _, _ = iie_shape_functions(xi * L, L, s["E"], s["G"], s["A"], s["I"], s["kappa"])
        assert np.allclose(N_w, Nw, atol=1e-12 * max(1, L))
        assert np.allclose(N_t * L, Nt * L, atol=1e-12)


@pytest.mark.parametrize("L", LENGTHS)
def test_element_symmetric_definite_with_rigid_body_null_space(L):
    K, M = (A[0] for A in element.element_matrices([L], **SECTION))
    assert np.array_equal(K, K.T) and np.array_equal(M, M.T)
    D = np.diag([1.0, L, 1.0, L])  # θ scaled to a length: well-conditioned spectra
    k = la.eigvalsh(D @ K @ D)
    assert np.sum(np.abs(k) <= 1e-12 * k.max()) == 2 and k.min() > -1e-12 * k.max()
    assert la.eigvalsh(D @ M @ D).min() > 0
    translation = np.array([1.0, 0.0, 1.0, 0.0])
    rotation = np.array([-L / 2, 1.0, L / 2, 1.0])  # w = x θ0 about the centre, θ = θ0
    for v in (translation, rotation):
        assert np.abs(K @ v).max() <= 1e-12 * np.abs(K).max() * np.abs(v).max()


def test_free_free_assembly_has_exactly_the_two_rigid_body_modes():
    beam = default_beam()
    n = 7
    M, K = beam.matrices(n, grading=10.0, clamped=False)
    K = K.toarray()
    x = beam.node_coordinates(n, 10.0)
    translation = np.zeros(2 * n + 2)
    translation[0::2] = 1.0
    rotation = np.zeros(2 * n + 2)
    rotation[0::2], rotation[1::2] = x, 1.0
    for v in (translation, rotation):
        assert np.abs(K @ v).max() <= 1e-11 * np.abs(K).max()
    h = beam.element_lengths(n, 10.0)
    D = np.diag(np.stack([np.ones(n + 1), np.concatenate([[h[0]], h])], axis=1).ravel())  # θ -> length
    k = la.eigvalsh(D @ K @ D)
    assert np.sum(np.abs(k) <= 1e-12 * k.max()) == 2
    assert k[2] > 1e6 * np.abs(k[:2]).max()  # a clear gap to the first flexible mode
    assert la.eigvalsh(D @ M.toarray() @ D).min() > 0


# ---------------------------------------------------------------------------- statics
@pytest.mark.parametrize("height", [1e-5, 1e-3, 0.05, 0.5])
@pytest.mark.parametrize("n, grading", [(1, 1.0), (5, 10.0)])
def test_end_loaded_cantilever_is_exact_at_every_node_no_shear_locking(height, n, grading):
    beam = TimoshenkoBeam(length=1.0, width=0.02, height=height, E=210e9, rho=7850.0)
    _, K = beam.matrices(n, grading)
    P = 1.0
    f = np.zeros(2 * n)
    f[2 * n - 2] = P
    q = la.solve(K.toarray(), f)
    x = beam.node_coordinates(n, grading)[1:]
    EI, kGA = beam.E * beam.inertia, beam.shear_factor * beam.shear_modulus * beam.area
    w = P / EI * (beam.length * x**2 / 2 - x**3 / 6) + P * x / kGA
    theta = P / EI * (beam.length * x - x**2 / 2)
    assert np.allclose(q[0::2], w, rtol=1e-9, atol=0)
    assert np.allclose(q[1::2], theta, rtol=1e-9, atol=0)


# ---------------------------------------------------------------------------- dynamics
def test_slender_cantilever_gives_euler_bernoulli_roots():
    f = SLENDER.model(200, grading=1.0, massless_tip=False).linear_frequencies(3)
    err = beta_l(SLENDER, f) / BETA_L[:3] - 1
    assert np.all(np.abs(err) < 1e-6), err
    # what is left is the continuum's own shear and rotary-inertia correction
    assert np.allclose(f, continuum_frequencies(SLENDER, 3), rtol=2e-7, atol=0)
    # the convenience closed form agrees with the roots above
    assert np.allclose(SLENDER.euler_bernoulli_frequencies(3), f, rtol=2e-6, atol=0)


def test_euler_bernoulli_helper_beyond_the_tabulated_roots():
    f = SLENDER.euler_bernoulli_frequencies(6)
    assert np.allclose(beta_l(SLENDER, f), [*BETA_L, 9 * np.pi / 2, 11 * np.pi / 2], rtol=1e-12)


def test_stubby_beam_converges_to_continuum_timoshenko():
    exact = continuum_frequencies(STUBBY, 3)
    f = STUBBY.model(400, grading=1.0, massless_tip=False).linear_frequencies(3)
    err = f / exact - 1
    assert np.all(err > 0), err  # Rayleigh-Ritz: FE frequencies lie above
    assert np.all(err < 1e-5), err
    # shear and rotary inertia matter here: Euler-Bernoulli is off by > 3 %
    assert np.all(STUBBY.euler_bernoulli_frequencies(3) / exact - 1 > 0.03)


@pytest.mark.parametrize("beam, rate", [(STUBBY, 2.0), (TimoshenkoBeam(0.5, 0.02, 5e-4, 210e9, 7850.0), 4.0)],
                         ids=["L/h=5", "L/h=1000"])
def test_mesh_convergence_rate_of_first_frequency(beam, rate):
    """Uniform meshes, slope of log(error) against log(h).

    The IIE's shear strain w' − θ is constant per element, so for a stubby beam the
    energy-norm error is O(h) and the eigenvalue error O(h²) (measured 2.08). For a slender
    beam the shear energy is negligible and the element is the cubic Hermite one, whose
    eigenvalue error is O(h⁴) (measured 3.96); the h² term returns only at tiny errors.
    """
    exact = continuum_frequencies(beam, 1)[0]
    ns = np.array([2, 4, 8, 16, 32])
    err = np.array([beam.model(int(n), 1.0, massless_tip=False).linear_frequencies(1)[0] / exact - 1
                    for n in ns])
    assert np.all(err > 0)
    slope = np.polyfit(np.log(beam.length / ns), np.log(err), 1)[0]
    assert abs(slope - rate) < 0.3, slope


# ---------------------------------------------------------------------------- mesh
@pytest.mark.parametrize("n, grading", [(2, 10.0), (8, 10.0), (21, 10.0), (21, 0.25), (5, 1.0)])
def test_graded_lengths(n, grading):
    h = mesh.graded_lengths(0.5, n, grading)
    assert h.shape == (n,) and np.all(h > 0)
    assert np.isclose(h.sum(), 0.5, rtol=1e-14)
    assert np.isclose(h[0] / h[-1], grading, rtol=1e-12)
    assert np.allclose(h[1:] / h[:-1], h[1] / h[0], rtol=1e-12)  # geometric
    x = mesh.node_coordinates(h)
    assert x[0] == 0.0 and np.isclose(x[-1], 0.5, rtol=1e-14) and np.all(np.diff(x) > 0)


def test_uniform_and_single_element_meshes():
    assert np.allclose(mesh.graded_lengths(2.0, 4, 1.0), 0.5, rtol=1e-15)
    assert np.array_equal(mesh.graded_lengths(2.0, 1, 10.0), [2.0])
    h = default_beam().element_lengths(21, 10.0)
    assert h[0] > h[-1]  # refined toward the tip


@pytest.mark.parametrize("args, match", [((0.0, 3, 1.0), "length"), ((1.0, 0, 1.0), "n_elements"),
                                         ((1.0, 3, 0.0), "grading"), ((1.0, 3, -2.0), "grading")])
def test_graded_lengths_rejects_bad_input(args, match):
    with pytest.raises(ValueError, match=match):
        mesh.graded_lengths(*args)


# ---------------------------------------------------------------------------- assembly
@pytest.mark.parametrize("clamped", [True, False])
def test_vectorised_assembly_equals_loop_assembly(clamped):
    beam = default_beam()
    n = 9
    M, K = beam.matrices(n, grading=10.0, clamped=clamped)
    Mn, Kn = beam_matrices(beam.element_lengths(n, 10.0), **beam.section(), clamped=clamped)
    assert M.shape == K.shape == (2 * n + 2 * (not clamped),) * 2
    assert np.allclose(K.toarray(), Kn, rtol=0, atol=1e-12 * np.abs(Kn).max())
    assert np.allclose(M.toarray(), Mn, rtol=0, atol=1e-12 * np.abs(Mn).max())


def test_assemble_sums_shared_node_and_removes_dofs():
    Ae = np.arange(32.0).reshape(2, 4, 4)
    A = assembly.assemble(Ae, assembly.chain_dofs(2)).toarray()
    assert A.shape == (6, 6)
    assert A[2, 3] == Ae[0, 2, 3] + Ae[1, 0, 1]
    assert A[0, 4] == 0.0
    R = assembly.remove_dofs(A, assembly.clamped_root_dofs()).toarray()
    assert np.array_equal(R, A[2:, 2:])


# ---------------------------------------------------------------------------- the beam model
def test_beam_model_layout_and_description():
    beam = default_beam()
    n = 8
    model = beam.model(n)
    assert model.n_dof == 2 * n
    assert model.contact_dof == 2 * n - 2 and model.stop_side == 1 and model.gap == beam.gap
    assert model.c.tolist() == [2 * n - 2, 2 * n - 1]  # tip deflection and rotation massless
    desc = json.loads(json.dumps(model.description))
    assert desc["kind"] == "TimoshenkoBeam" and desc["n_elements"] == n and desc["grading"] == 10.0
    assert desc["massless_tip"] is True and desc["height"] == beam.height
    again = TimoshenkoBeam.rebuild(desc)
    assert (again.M != model.M).nnz == 0 and (again.K != model.K).nnz == 0
    assert mmshbm.TimoshenkoBeam is TimoshenkoBeam and mmshbm.default_beam is default_beam


def test_massless_tip_model_keeps_the_full_mass_frequencies():
    """Default beam, 21 elements, grading 10: f1 ≈ 45.8 Hz (45.09 with tip mass),
    f2 ≈ 286 Hz (281.6). Dropping the tip node's mass raises them by 1.60 % here, which
    is the first-order Rayleigh estimate of removing that mass, not a modelling error
    (under 1 % needs grading >= 20 at 21 elements)."""
    beam = default_beam()
    massless = beam.model(21, 10.0, massless_tip=True)
    full = beam.model(21, 10.0, massless_tip=False)
    fm = massless.linear_frequencies(3)
    ff, phi = full.linear_modes(3)
    assert 44.0 < fm[0] < 47.0 and 278.0 < fm[1] < 292.0
    shift = fm / ff - 1
    assert np.all((shift > 0) & (shift < 0.02)), shift
    dM = (full.M - massless.M).toarray()
    rayleigh = 1 / np.sqrt(1 - np.einsum("ik,ij,jk->k", phi, dM, phi)) - 1
    assert np.isclose(shift[0], rayleigh[0], rtol=0.02)
    # the full-mass model is the continuum beam (L/h = 37) to 2e-7 in f1
    assert np.isclose(ff[0], continuum_frequencies(beam, 1)[0], rtol=1e-6)
    # grading toward the tip is what keeps the shift small
    uniform = beam.model(21, 1.0, massless_tip=True).linear_frequencies(1)[0] / ff[0] - 1
    finer = beam.model(21, 20.0, massless_tip=True).linear_frequencies(1)[0] / ff[0] - 1
    assert finer < 0.01 < shift[0] < uniform
