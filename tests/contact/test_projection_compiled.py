"""The compiled projection (mmshbm.contact.projection, .unilateral) against the plain-NumPy one of
tests/naive.py: the same spectrum composed with a Python product matrix (exact rule), or
a dense DFT of the sample indicator (sampled rule), and the damped contact residual
against its Python loop."""

import functools

import naive
import numpy as np
import pytest

import mmshbm
from mmshbm.contact.projection import contact_spectrum, sample_tables
from mmshbm.contact.unilateral import project_contact
from mmshbm.methods.mms.forced import ForcedResponseProblem

CASES = [(1, -np.inf, 0.3), (3, -0.5, 0.2), (5, -0.2, np.inf), (8, -0.4, 0.4), (20, -np.inf, 0.1),
         (30, -0.3, 0.3), (40, -np.inf, 0.05)]


def _p(H, seed):
    return np.random.default_rng(seed).normal(size=2 * H + 1) / np.sqrt(np.arange(1, 2 * H + 2))


@pytest.mark.parametrize("H, lo, hi", CASES)
def test_exact_projection_equals_the_python_composition(H, lo, hi):
    for seed in range(3):
        p = _p(H, seed)
        r, G = project_contact(p, lo, hi)
        r0, G0 = naive.project_contact(p, lo, hi, contact_spectrum)
        np.testing.assert_allclose(G, G0, rtol=0, atol=1e-15)
        np.testing.assert_allclose(r, r0, rtol=0, atol=1e-14 * np.abs(p).sum())


@pytest.mark.parametrize("H, lo, hi", CASES)
def test_sampled_projection_equals_a_dense_dft(H, lo, hi):
    N = 4 * H + 7

    def spectrum(c, s):
        g = np.fft.irfft(np.concatenate([[c[0]], 0.5 * (c[1:] - 1j * s[1:]), np.zeros(N // 2 + 1 - len(c))]),
                         n=N) * N
        C, S = naive.sampled_spectrum(g)
        return C[:2 * H + 1], S[:2 * H + 1]

    for seed in range(3):
        p = _p(H, seed)
        r, G = project_contact(p, lo, hi, exact=False, n_samples=N)
        r0, G0 = naive.project_contact(p, lo, hi, spectrum)
        np.testing.assert_allclose(G, G0, rtol=0, atol=1e-13)
        np.testing.assert_allclose(r, r0, rtol=0, atol=1e-13 * np.abs(p).sum())


def test_tables_are_built_once():
    assert sample_tables(5, 176) is sample_tables(5, 176)
    tau, cos_t, sin_t = sample_tables(5, 176)
    np.testing.assert_array_equal(cos_t[3], np.cos(3 * tau))
    assert cos_t.shape == sin_t.shape == (11, 176)


@functools.cache
def _forced(H, projection):
    m = mmshbm.default_beam().model(8).with_damping(modal_ratio=0.02)
    F = np.zeros(m.n_dof)
    F[m.l[-2]] = 5.0
    return ForcedResponseProblem(m, F, harmonics=H, stability=False, projection=projection)


def _python_rows(p, x, F, dF, dFp, exact):
    """The contact residual by a Python loop over contacts with the NumPy projection."""
    spectrum = functools.partial(contact_spectrum, exact=exact, n_samples=None if exact else p.N)
    R, Jx, Jp = F.copy(), dF.copy(), dFp.copy()
    for j, i in enumerate(p.contact_rows):
        idx = p._coef_index[i]
        r = p.r[j]
        phi, G = naive.project_contact(x[idx] - F[idx] / r, p.lo[j], p.hi[j], spectrum)
        R[idx] = F[idx] + r * phi
        A = np.eye(p.n_coef) - G
        Jx[idx] = A @ dF[idx]
        Jx[np.ix_(idx, idx)] += r * G
        Jp[idx] = A @ dFp[idx]
    return R, Jx, Jp


@pytest.mark.parametrize("H, projection", [(3, "exact"), (10, "exact"), (5, "sampled")])
def test_damped_contact_residual_equals_the_python_loop(H, projection):
    p = _forced(H, projection)
    rng = np.random.default_rng(H)
    for _ in range(3):
        x = rng.normal(size=p.n_x) * p.xscale * 3
        F = rng.normal(size=p.n_x) * p.rowscale
        dF = rng.normal(size=(p.n_x, p.n_x))
        dFp = rng.normal(size=(p.n_x, 2))
        got = p.contact_residual(x, F, dF, dFp)
        want = _python_rows(p, x, F, dF, dFp, projection == "exact")
        for a, b in zip(got, want, strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(b).max())


@pytest.mark.parametrize("H, projection", [(3, "exact"), (12, "exact"), (5, "sampled")])
def test_fused_damped_residual_equals_the_dense_blocks(H, projection):
    """F = 𝔇 x − load with 𝔇 dense (``real_blocks``) through the Python composition, against
    the fused kernel (𝔇 never formed)."""
    p = _forced(H, projection)
    rng = np.random.default_rng(H + 1)
    shape = (H + 1, p.n_c, p.n_c)
    for _ in range(3):
        D = (rng.normal(size=shape) + 1j * rng.normal(size=shape)) * p.rowscale[0] / p.xscale[0]
        dD = rng.normal(size=(2,) + shape) + 1j * rng.normal(size=(2,) + shape)
        x = rng.normal(size=p.n_x) * p.xscale * 3
        load = rng.normal(size=p.n_x) * p.rowscale
        dload = rng.normal(size=(p.n_x, 2))
        F = p.real_blocks(D) @ x - load
        dFp = np.column_stack([p.real_blocks(dD[i]) @ x - dload[:, i] for i in range(2)])
        want = _python_rows(p, x, F, p.real_blocks(D), dFp, projection == "exact")
        got = p.fused_residual(D, x, load, dD, dload)
        for a, b in zip(got, want, strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(b).max())
        np.testing.assert_allclose(p.fused_residual(D, x, load)[0], want[0], rtol=1e-12,
                                   atol=1e-12 * np.abs(want[0]).max())
