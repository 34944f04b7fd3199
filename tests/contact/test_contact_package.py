"""The per-point measures: the peak measure, the harmonic content and the energy are each
defined once (in mmshbm.core.measures) and give the closed-form values."""

from __future__ import annotations

import ast

import numpy as np
import pytest
from locations import PACKAGE as PACKAGE_DIR
from roundoff import assert_roundoff_close

from mmshbm import Model
from mmshbm.core import measures

PACKAGE = PACKAGE_DIR

# ---------------------------------------------------------------------------- defined once
#: the measures, by every name they had; each may be defined only in core/measures.py
MEASURES = {"harmonic_content", "refined_max", "_refined_max", "refined_peak", "amplitude_peak",
            "amplitude_sign", "_series_peak", "_cosine_peak", "mean_energy", "_mean_energy",
            "condensed_energy", "_condensed_energy", "sample_coefficients", "check_dof"}


def _trees():
    for path in sorted(PACKAGE.rglob("*.py")):
        yield path.relative_to(PACKAGE).as_posix(), ast.parse(path.read_text())


def test_measures_are_defined_once():
    where: dict[str, list[str]] = {}
    for rel, tree in _trees():
        for node in tree.body:  # module-level functions
            if isinstance(node, ast.FunctionDef) and node.name in MEASURES:
                where.setdefault(node.name, []).append(rel)
    elsewhere = {name: files for name, files in where.items() if files != ["core/measures.py"]}
    assert not elsewhere, f"measures defined outside core/measures.py: {elsewhere}"
    assert set(where) == MEASURES - {"_refined_max", "refined_peak", "_mean_energy", "_condensed_energy"}


def _calls(node) -> set[str]:
    out = set()
    for sub in ast.walk(node):
        if isinstance(sub, ast.Call):
            f = sub.func
            out.add(f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", ""))
    return out


def test_solvers_harmonic_content_calls_the_one_definition():
    """Every solver's ``harmonic_content`` method either delegates to another solver (the
    results) or calls :func:`mmshbm.core.measures.harmonic_content`; none computes the
    magnitudes itself."""
    methods = []
    for rel, tree in _trees():
        for cls in (n for n in ast.walk(tree) if isinstance(n, ast.ClassDef)):
            for fn in cls.body:
                if isinstance(fn, ast.FunctionDef) and fn.name == "harmonic_content":
                    methods.append((rel, cls.name, _calls(fn)))
    assert len(methods) >= 8
    for rel, cls, calls in methods:
        assert "harmonic_content" in calls, f"{rel}:{cls}.harmonic_content"
        assert not calls & {"hypot", "rfft", "abs"}, f"{rel}:{cls}.harmonic_content computes |Q_k| itself"


def test_the_parabola_peak_is_written_once():
    """The parabola through a sampled peak (y0 − (y₊ − y₋)²/(8 (y₋ − 2y0 + y₊))) appears in
    one module."""
    hits = [rel for rel, tree in _trees() if "0.125 * (yp - ym) ** 2" in ast.unparse(tree)]
    assert hits == ["core/measures.py"]


# ---------------------------------------------------------------------------- values
def test_harmonic_content_of_known_coefficients():
    Q = np.array([-0.5, 3.0, 4.0, 0.0, -2.0])
    # |c + is| by hypot: libm's hypot is within an ulp, not correctly rounded everywhere
    assert_roundoff_close(measures.harmonic_content(Q), [0.5, 5.0, 2.0], [0.5, 5.0, 2.0])
    with pytest.raises(ValueError, match="2H\\+1"):
        measures.harmonic_content(np.zeros(4))


def test_sample_coefficients_recover_a_trigonometric_polynomial():
    """Equispaced samples of a degree-3 polynomial: the DFT returns its coefficients to
    round-off (N = 16 > 2·3, no aliasing)."""
    Q = np.array([0.3, 1.0, -0.5, 0.0, 0.25, -0.125, 0.0625])
    tau = 2 * np.pi * np.arange(16) / 16
    k = np.arange(1, 4)
    q = Q[0] + np.cos(np.outer(tau, k)) @ Q[1::2] + np.sin(np.outer(tau, k)) @ Q[2::2]
    np.testing.assert_allclose(measures.sample_coefficients(q, 3), Q, atol=1e-15)
    with pytest.raises(ValueError, match="harmonics"):
        measures.sample_coefficients(q, 8)


def test_refined_max_of_a_sampled_cosine():
    """A cos τ sampled 64 times with the peak midway between two samples. The parabola
    through the largest sample (τ = h/2) and its neighbours (τ = −h/2, 3h/2) misses cos by
    at most max|f‴|/6 · |Π(τ − τ_i)| <= (3h/2 A)/6 · 3h³/8 < A h⁴/8 near the peak
    (h = 2π/64: 1.2e-5 A), far below the raw sample's miss A (1 − cos(h/2)) ≈ 1.2e-3 A."""
    A, n = 2.0, 64
    tau = 2 * np.pi * (np.arange(n) + 0.5) / n
    y = A * np.cos(tau)
    h = 2 * np.pi / n
    assert abs(measures.refined_max(y) - A) <= A * h**4 / 8
    assert A - y.max() > 100 * A * h**4 / 8
    assert measures.amplitude_peak(-y, 1) == measures.refined_max(y)  # away from an upper stop
    assert measures.amplitude_peak(-y, 0) == measures.refined_max(np.abs(y))


def test_mean_energy_of_a_linear_mode():
    """Harmonic motion q = A cos Ωτ of k, m at Ω² = k/m: the period averages of kinetic and
    potential energy are each ¼ k A², the total ½ k A² (closed form)."""
    k, m, A = 4.0, 1.0, 0.3
    model = Model.from_matrices(np.diag([m, 0.0]), np.array([[k + 1e3, -1e3], [-1e3, 1e3]]), contact_dof=1,
                                gap=1.0, stop_side=1)
    Q = np.zeros((2, 3))
    Q[0, 1] = A
    Q[1, 1] = A  # the massless DOF moving with the mass: its spring (1e3) unstretched
    omega = np.sqrt(k / m)
    np.testing.assert_allclose(measures.mean_energy(model, Q, omega), 0.5 * k * A**2, rtol=1e-14)


def test_the_lcp_solvers_agree():
    """Principal pivoting (compiled), the least-squares enumeration and the active-set
    enumeration solve the same LCPs: random positive definite G (4 contacts), free gaps of
    both signs. λ agrees to the round-off of the solves (cond(G) <= 1e3 here: 1e-12 of
    |h|/λ_min(G) bounds it), the active sets exactly."""
    from mmshbm.contact.lcp import lcp_active_sets, lcp_enumerated, lcp_solve

    rng = np.random.default_rng(7)
    for _ in range(20):
        B = rng.standard_normal((4, 4))
        G = B @ B.T + 0.5 * np.eye(4)
        assert np.linalg.cond(G) < 1e3
        H = rng.standard_normal((4, 6))
        lam, act = lcp_solve(G, H)
        sets = lcp_active_sets(G, H, np.arange(4))
        for j in range(H.shape[1]):
            ref = lcp_enumerated(G, H[:, j])
            scale = np.abs(H[:, j]).max() / np.linalg.eigvalsh(G)[0]
            np.testing.assert_allclose(lam[:, j], ref, rtol=0, atol=1e-12 * scale)
            assert tuple(np.flatnonzero(act[:, j])) == tuple(sets[j]) == tuple(np.flatnonzero(ref > 0))
            g = H[:, j] + G @ ref
            assert g.min() >= -1e-12 * scale * np.abs(G).max() and abs(g @ ref) <= 1e-10 * scale**2


def test_check_dof():
    assert measures.check_dof(None, 3, 2) == 2
    assert measures.check_dof(1, 3, 2) == 1
    with pytest.raises(ValueError, match="dof must be in"):
        measures.check_dof(3, 3, 0)
