"""Property-based tests (hypothesis): identities that must hold for every input.

They extend tests/harmonic/test_harmonics.py, test_kernels.py and test_fe.py (which check the same
objects at chosen points) with: time-shift equivariance of the transforms and of the
MMS-HBM residual, the min-form of the proximal map, random sections and meshes for the
element matrices, and the condensation kernel at random frequencies.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import scipy.linalg as la
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from naive import (
    condensed_stiffness_dense,
    element_by_quadrature,
    mmshbm_full_residual,
    shift_coefficients,
)

import mmshbm
from mmshbm.contact.unilateral import proximal_contact
from mmshbm.fe import assembly, element
from mmshbm.fe.oscillator import OneDofOscillator
from mmshbm.harmonic.condense import Condensation
from mmshbm.harmonic.harmonics import HarmonicTransform
from mmshbm.methods.mms.conservative import MMSHBMProblem

seeds = st.integers(0, 2**32 - 1)


# ---------------------------------------------------------------------------- transforms
@settings(max_examples=40, deadline=None)
@given(st.integers(1, 10), st.integers(0, 30), st.integers(0, 200), seeds)
def test_shifting_samples_rotates_coefficients(H, extra, m, seed):
    """x(τ + 2πm/N) sampled = the samples rolled by m; its coefficients are those of x
    rotated harmonic by harmonic (exact for a band-limited x)."""
    N = 2 * H + 1 + extra
    m %= N
    rng = np.random.default_rng(seed)
    coeffs = rng.normal(size=(1, 2 * H + 1))
    tr = HarmonicTransform(H, N, 1)
    x = tr.to_time(coeffs)
    A = np.concatenate([coeffs[:, :1], coeffs[:, 1::2]], axis=1).T
    B = np.concatenate([[[0.0]], coeffs[:, 2::2]], axis=1).T
    A2, B2 = shift_coefficients(A, B, 2 * np.pi * m / N)
    shifted = np.empty_like(coeffs)
    shifted[0, 0], shifted[0, 1::2], shifted[0, 2::2] = A2[0, 0], A2[1:, 0], B2[1:, 0]
    scale = 1 + np.abs(coeffs).sum()
    np.testing.assert_allclose(tr.to_time(shifted), np.roll(x, -m, axis=-1), atol=1e-12 * scale)
    np.testing.assert_allclose(tr.to_harmonics(np.roll(x, -m, axis=-1)), shifted, atol=1e-12 * scale)


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 10), st.integers(0, 30), seeds)
def test_projection_is_an_orthogonal_projector_with_parseval(H, extra, seed):
    N = 2 * H + 1 + extra
    rng = np.random.default_rng(seed)
    y = rng.normal(size=(2, N))
    tr = HarmonicTransform(H, N, 2)
    c = tr.to_harmonics(y)
    np.testing.assert_allclose(tr.to_harmonics(tr.to_time(c)), c, atol=1e-12 * np.abs(y).sum())
    x = tr.to_time(c)
    # Parseval for the band-limited part: mean x² = c0² + ½ Σ (c_k² + s_k²), when N > 2H
    # the Nyquist term is absent and the residual y − x is orthogonal to x
    if N > 2 * H:
        np.testing.assert_allclose(np.mean(x * x, axis=1), c[:, 0] ** 2 + 0.5 * np.sum(c[:, 1:] ** 2, axis=1),
                                   rtol=1e-11)
        np.testing.assert_allclose(np.sum((y - x) * x, axis=1), 0.0, atol=1e-11 * np.sum(y * y))


# ---------------------------------------------------------------------------- proximal map
finite = st.floats(-1e6, 1e6, allow_nan=False)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(finite, finite), min_size=1, max_size=40), st.floats(1e-6, 1e8))
def test_proximal_residual_is_the_min_function(pairs, r):
    """λ − prox_{R+}(λ − r g) = min(λ, r g): zero exactly when 0 <= g ⊥ λ >= 0 (r > 0),
    and the active set is λ > r g."""
    lam, g = (np.array(v) for v in zip(*pairs, strict=True))
    R, active = proximal_contact(lam, g, r)
    rg = r * g
    np.testing.assert_allclose(R, np.minimum(lam, rg), rtol=0, atol=4e-16 * (np.abs(lam) + np.abs(rg)).max())
    np.testing.assert_array_equal(active, (lam - rg > 0).astype(float))


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(finite, finite), min_size=1, max_size=40), st.floats(1e-6, 1e8),
       st.floats(1e-6, 1e8))
@example([(1.0, 5e-324)], 0.5, 0.5)  # found by hypothesis: r·g lost in λ − r g
@example([(1e6, 1e-6)], 1e-6, 1e8)
@example([(0.0, -5e-324)], 0.5, 1.0)  # found by hypothesis: r·g underflows to −0
def test_proximal_fixed_points_are_complementary_for_every_r(pairs, r1, r2):
    """Fixed points λ = prox(λ − r g) do not depend on r, and satisfy 0 <= g ⊥ λ >= 0 up to
    the rounding of λ − r g (an r·g below half an ulp of λ is lost in it: λ = 1, g = 5e-324
    is a fixed point in floating point)."""
    lam, g = (np.array(v) for v in zip(*pairs, strict=True))
    # make about half of the pairs complementary: open (λ = 0, g >= 0) or closed (g = 0, λ >= 0)
    k = len(lam) // 2
    lam[:k] = np.where(np.arange(k) % 2 == 0, 0.0, np.abs(lam[:k]))
    g[:k] = np.where(np.arange(k) % 2 == 0, np.abs(g[:k]), 0.0)
    R1, _ = proximal_contact(lam, g, r1)
    R2, _ = proximal_contact(lam, g, r2)
    fixed = R1 == 0
    lost = np.abs(lam) * 2.0**-52  # r·g at or below this may vanish in λ − r g
    clear = (g == 0) | ((r1 * np.abs(g) > lost) & (r2 * np.abs(g) > lost))
    np.testing.assert_array_equal(fixed[clear], (R2 == 0)[clear])
    assert np.all(fixed[:k])
    # g >= 0 up to an r·g lost in λ − r g (also one that underflows: g = −5e-324, r = 0.5)
    assert np.all(lam[fixed] >= 0) and np.all((g[fixed] >= 0) | (r1 * g[fixed] >= -lost[fixed]))
    assert np.all(np.minimum(lam[fixed], r1 * g[fixed]) <= lost[fixed])  # complementary to round-off
    assert np.all(lam[fixed & clear] * g[fixed & clear] == 0)
    np.testing.assert_array_equal(lam[fixed], np.maximum(0.0, lam[fixed] - r1 * g[fixed]))


# ---------------------------------------------------------------------------- element matrices
sections = st.fixed_dictionaries({
    "L": st.floats(1e-3, 2.0), "E": st.floats(1e9, 5e11), "nu": st.floats(0.0, 0.49),
    "rho": st.floats(1e3, 2e4), "b": st.floats(1e-3, 0.2), "h": st.floats(1e-3, 0.2),
    "kappa": st.floats(0.5, 1.0),
})


def _section(s):
    A, I = s["b"] * s["h"], s["b"] * s["h"] ** 3 / 12
    return {"E": s["E"], "G": s["E"] / (2 * (1 + s["nu"])), "rho": s["rho"], "A": A, "I": I,
            "kappa": s["kappa"]}


@settings(max_examples=60, deadline=None)
@given(sections)
def test_element_symmetric_with_exactly_the_rigid_body_null_space(s):
    L, sec = s["L"], _section(s)
    K, M = (X[0] for X in element.element_matrices([L], **sec))
    assert np.array_equal(K, K.T) and np.array_equal(M, M.T)
    D = np.diag([1.0, 1 / L, 1.0, 1 / L])  # in (w, Lθ): entries of one order
    Ks, Ms = D @ K @ D, D @ M @ D
    k = la.eigvalsh(Ks)
    assert np.sum(k <= 1e-10 * k.max()) == 2 and k.min() >= -1e-10 * k.max()
    assert la.eigvalsh(Ms).min() > 0
    rigid = np.array([[1.0, 0.0, 1.0, 0.0], [-L / 2, 1.0, L / 2, 1.0]]).T  # translation, rotation
    assert np.abs(K @ rigid).max() <= 1e-10 * np.abs(K).max() * np.abs(rigid).max()
    # the rigid-body motions carry their exact kinetic energy: mass ρAL, inertia about the centre
    m_total = rigid[:, 0] @ M @ rigid[:, 0]
    assert abs(m_total / (sec["rho"] * sec["A"] * L) - 1) < 1e-12


@settings(max_examples=25, deadline=None)
@given(sections)
def test_element_equals_quadrature_of_the_timoshenko_energy(s):
    L, sec = s["L"], _section(s)
    K, M = (X[0] for X in element.element_matrices([L], **sec))
    Kq, Mq = element_by_quadrature(L, sec["E"], sec["G"], sec["rho"], sec["A"], sec["I"], sec["kappa"])
    D = np.diag([1.0, 1 / L, 1.0, 1 / L])
    np.testing.assert_allclose(D @ K @ D, D @ Kq @ D, rtol=0, atol=1e-9 * np.abs(D @ Kq @ D).max())
    np.testing.assert_allclose(D @ M @ D, D @ Mq @ D, rtol=0, atol=1e-9 * np.abs(D @ Mq @ D).max())


@settings(max_examples=20, deadline=None)
@given(st.integers(1, 12), st.floats(0.1, 20.0), sections)
def test_assembled_beam_has_two_rigid_modes_free_and_none_clamped(n, grading, s):
    lengths = mmshbm.fe.mesh.graded_lengths(s["L"], n, grading)
    Ke, Me = element.element_matrices(lengths, **_section(s))
    dofs = assembly.chain_dofs(n)
    K = assembly.assemble(Ke, dofs).toarray()
    M = assembly.assemble(Me, dofs).toarray()
    x = np.concatenate([[0.0], np.cumsum(lengths)])
    d = np.ones(2 * n + 2)
    d[1::2] = n / s["L"]  # rotations times the mean element length
    Ks = d[:, None] * K * d[None, :]
    k = la.eigvalsh(Ks)
    assert np.sum(np.abs(k) <= 1e-9 * k.max()) == 2
    translation = np.zeros(2 * n + 2)
    translation[0::2] = 1.0
    rotation = np.zeros(2 * n + 2)
    rotation[0::2], rotation[1::2] = x, 1.0  # w = x θ0, θ = θ0 about the root
    for v in (translation, rotation):
        assert np.abs(K @ v).max() <= 1e-9 * np.abs(K).max() * np.abs(v).max()
    assert la.eigvalsh(M).min() > 0
    kc = la.eigvalsh(Ks[2:, 2:])
    assert kc.min() > 1e-12 * kc.max()  # clamping removes both


# ---------------------------------------------------------------------------- MMS-HBM residual
@cache
def _problem(name: str, projection: str = "sampled") -> MMSHBMProblem:
    """Sampled projection by default: the naive loop-over-samples reference is that rule;
    no pole unknowns (the reference has none; tests/methods/test_poles.py checks them)."""
    if name == "oscillator":
        return MMSHBMProblem(OneDofOscillator(1.0, 1.0, 4.0, 1.0).model(), 5, projection=projection,
                             poles=False)
    return MMSHBMProblem(mmshbm.default_beam().model(8), 3, projection=projection, poles=False)


@cache
def _branch(name: str):
    p = _problem(name)
    return mmshbm.backbone(p.model, harmonics=p.H, max_steps=60, projection="sampled", poles=False)


@cache
def _clamped_frequencies(name: str) -> np.ndarray:
    b = _problem(name).model.blocks
    return np.sqrt(la.eigvalsh(b["K_ll"].toarray(), b["M_ll"].toarray()))


def _random_state(name, seed, omega_factor, projection="sampled"):
    """Random scaled unknowns (coefficients of order the gap), Ω = factor·ω_ref away from
    the poles kΩ = ω_j of the condensation."""
    p = _problem(name, projection)
    rng = np.random.default_rng(seed)
    u = rng.normal(size=p.n_unknowns) * np.concatenate([2.0 ** -np.arange(p.H + 1).repeat(p.n_c), [0.0]])
    u[-1] = omega_factor
    omega = p.unpack(u)[1]
    k = np.arange(1, p.H + 1)[:, None]
    assume(np.min(np.abs(k * omega / _clamped_frequencies(name)[None, :] - 1)) > 1e-3)
    return p, u


@settings(max_examples=30, deadline=None)
@given(st.sampled_from(["oscillator", "beam"]), seeds, st.floats(0.5, 2.0))
def test_residual_and_jacobian_are_equivariant_under_a_half_period_shift(name, seed, factor):
    """τ → τ + π maps a cosine state a_k to (−1)^k a_k; the residual rows of harmonic k
    pick up (−1)^k, the Jacobian (−1)^(k+m) (Ω column: (−1)^k). With the cosine ansatz
    this is the only time shift that stays in the ansatz."""
    p, u = _random_state(name, seed, factor)
    sign_rows = np.repeat((-1.0) ** np.arange(p.H + 1), p.n_c)
    sign_cols = np.append(sign_rows, 1.0)
    R, J = p.evaluate(u)
    R, J = R.copy(), J.copy()
    R2, J2 = p.evaluate(u * sign_cols)
    np.testing.assert_allclose(R2, sign_rows * R, rtol=0, atol=1e-11 * max(1.0, np.abs(R).max()))
    np.testing.assert_allclose(J2, sign_rows[:, None] * J * sign_cols[None, :], rtol=0,
                               atol=1e-10 * np.abs(J).max())


@settings(max_examples=30, deadline=None)
@given(st.sampled_from(["oscillator", "beam"]), seeds, st.floats(0.5, 2.0))
def test_production_residual_is_the_cosine_part_of_the_full_reference(name, seed, factor):
    """The AFT residual (pyfftw + Numba) equals the DFT-matrix, loop-over-samples
    reference with the full Fourier ansatz restricted to cosines; the sine projections
    of an even state's residual vanish identically (the energy-balance identity drops
    out of the cosine system)."""
    p, u = _random_state(name, seed, factor)
    a, omega = p.unpack(u)
    full = mmshbm_full_residual(p, a, np.zeros_like(a), omega)
    R = (p.evaluate(u, jacobian=False) * p.rowscale).reshape(p.H + 1, p.n_c)
    scale = np.abs(full).max()
    np.testing.assert_allclose(R[0], full[0], rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(R[1:], full[1::2], rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(full[2::2], 0.0, atol=1e-11 * scale)


@settings(max_examples=15, deadline=None)
@given(st.sampled_from(["oscillator", "beam"]), seeds, st.floats(0.5, 2.0))
def test_exact_projection_is_the_limit_of_many_samples(name, seed, factor):
    """The exact (C¹) projection is the limit of the naive loop-over-samples rule as the
    samples grow: the integrand s·(p − θ) is continuous with kinks, so the sampled rule
    converges toward it like about 1/N², not monotonically (the constant depends on where
    the kinks fall between samples; e.g. 2.1e-6, 1.5e-7, 1.8e-9 at 2¹², 2¹⁴, 2¹⁶)."""
    p, u = _random_state(name, seed, factor, "exact")
    a, omega = p.unpack(u)
    R = (p.evaluate(u, jacobian=False) * p.rowscale).reshape(p.H + 1, p.n_c)

    def error(n):
        ref = mmshbm_full_residual(p, a, np.zeros_like(a), omega, n_samples=n)
        return np.abs(np.vstack([R[:1] - ref[:1], R[1:] - ref[1::2]])).max(), np.abs(ref).max()

    (e12, scale), (e16, _) = error(2**12), error(2**16)
    assert e16 <= 2e-8 * scale, (e12, e16)
    assert e16 < e12 or e12 <= 1e-12 * scale, (e12, e16)  # no error floor above the 2¹² rule's


@settings(max_examples=30, deadline=None)
@given(st.sampled_from(["oscillator", "beam"]), seeds, st.floats(0.5, 2.0), st.integers(0, 10**6))
def test_full_residual_is_equivariant_under_sample_shifts(name, seed, factor, m):
    """With cosines and sines, a shift by m samples (θ = 2πm/N) rotates the residual
    harmonic by harmonic, exactly (the AFT grid maps onto itself)."""
    p, u = _random_state(name, seed, factor)
    a, omega = p.unpack(u)
    b = np.random.default_rng(seed + 1).normal(size=a.shape) * np.abs(a).max()
    b[0] = 0.0
    theta = 2 * np.pi * (m % p.N) / p.N
    R = mmshbm_full_residual(p, a, b, omega)
    a2, b2 = shift_coefficients(a, b, theta)
    R2 = mmshbm_full_residual(p, a2, b2, omega)
    Rc = np.vstack([R[:1], R[1::2]])
    Rs = np.vstack([np.zeros_like(R[:1]), R[2::2]])
    Rc2, Rs2 = shift_coefficients(Rc, Rs, theta)
    scale = np.abs(R).max()
    np.testing.assert_allclose(R2[0], Rc2[0], atol=1e-10 * scale)
    np.testing.assert_allclose(R2[1::2], Rc2[1:], atol=1e-10 * scale)
    np.testing.assert_allclose(R2[2::2], Rs2[1:], atol=1e-10 * scale)


@settings(max_examples=30, deadline=None)
@given(st.sampled_from(["oscillator", "beam"]), st.integers(0, 10**6), st.integers(0, 10**6))
def test_a_time_shift_of_a_solution_is_a_solution(name, point, m):
    """Converged backbone points, shifted in time by any multiple of 2π/N (which gives
    them sine coefficients), are zeros of the full-ansatz residual."""
    p, br = _problem(name), _branch(name)
    u = br.states[point % len(br)]
    a, omega = p.unpack(u)
    a2, b2 = shift_coefficients(a, np.zeros_like(a), 2 * np.pi * (m % p.N) / p.N)
    R = mmshbm_full_residual(p, a2, b2, omega)
    rowscale = p.rowscale[: p.n_c]  # force scale per DOF (the contact row: k_c · gap)
    assert np.all(np.abs(R) <= 1e-8 * rowscale[None, :])


# ---------------------------------------------------------------------------- condensation kernel
@settings(max_examples=30, deadline=None)
@given(st.sampled_from(["oscillator", "beam"]), st.sampled_from(["banded", "splu"]), st.floats(0.05, 3.0))
def test_condensation_kernel_equals_dense_solves(name, backend, factor):
    p = _problem(name)
    omega = factor * p.omega_ref
    k = np.arange(1, p.H + 1)[:, None]
    assume(np.min(np.abs(k * omega / _clamped_frequencies(name)[None, :] - 1)) > 1e-3)
    D, dD = Condensation(p.model, backend).dynamic_stiffness(omega, p.H)
    D_ref, dD_ref = condensed_stiffness_dense(p.model, omega, p.H)
    for k in range(p.H + 1):
        scale = np.abs(D_ref[k]).max()
        np.testing.assert_allclose(D[k], D_ref[k], rtol=0, atol=1e-8 * scale)
        np.testing.assert_allclose(dD[k], dD_ref[k], rtol=0, atol=1e-8 * max(np.abs(dD_ref[k]).max(), 1e-300))
