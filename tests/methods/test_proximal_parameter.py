"""The proximal parameter r = "residual": its value, and the truncation error it removes.

At finite H the Galerkin solution of the proximal contact law depends on r
(mmshbm.methods.mms.proximal). With r the compliance of the harmonics the series drops,
the series is cut in the contact DOF's smooth quasi-static position instead of its own
kinked one. Checked against the exact event-driven orbit (mmshbm.exact) on chains whose
contact spring is 900-1900 times stiffer than the structure, where the default r leaves
errors of 1e-2 at H = 31.
"""

import numpy as np
import pytest
import scipy.linalg as la

import mmshbm
from mmshbm import exact
from mmshbm.methods.mms.conservative import MMSHBMProblem


def one_mass(m, k, kc, gap=0.01, side=1):
    """Mass m on a spring k to ground, a massless contact node on a spring kc."""
    M = np.diag([m, 0.0])
    K = np.array([[k + kc, -kc], [-kc, kc]])
    return mmshbm.Model.from_matrices(M, K, contact_dof=1, gap=gap, stop_side=side)


def three_masses():
    """Ground–m1–m2–m3–node: masses over two decades, the node's spring 5× the stiffest."""
    m = [0.0975033, 0.3105124, 21.8768584]
    k = [81.790870, 20635.6929, 16884.9784, 92672.8044]
    K = np.zeros((4, 4))
    K[0, 0] = k[0]
    for i, s in enumerate(k[1:]):
        K[np.ix_([i, i + 1], [i, i + 1])] += s * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return mmshbm.Model.from_matrices(np.diag(m + [0.0]), K, contact_dof=3, gap=0.01, stop_side=1)


def test_residual_r_is_the_clamped_stiffness_when_every_mode_lies_below_the_cut():
    """One DOF with mass: its mode is below (H+1)·ω₁, so the dropped harmonics see only the
    node's own spring: r = kc (up to the round-off of 1/D₀ − φ²/ω²: kc/k ~ 900)."""
    model = one_mass(2.0027, 38.071, 33749.83)
    p = MMSHBMProblem(model, 31, r="residual")
    # 1/r is the difference of two compliances ~900 times larger than it: the modal term's
    # round-off (~1e-13 relative, eigensolver included) grows to ~1e-10; 1e-7 bounds it on
    # any LAPACK while staying far below the 1e-3 a wrong rule would make
    assert p.r_each[0] == pytest.approx(33749.83, rel=1e-7)
    # the default keeps the static stiffness k·kc/(k + kc)
    series = 38.071 * 33749.83 / (38.071 + 33749.83)
    assert MMSHBMProblem(model, 31).r_each[0] == pytest.approx(series, rel=1e-12)


def test_residual_r_counts_the_modes_above_the_cut_as_static():
    """Three masses whose highest mode lies above (H+1)·ω₁ for small H: r is the inverse
    of the static compliance minus the modes below the cut, computed here from a dense
    generalised eigensolution of the condensed matrices; it rises to kc as H grows."""
    model = three_masses()
    K = model.K.toarray()
    M = model.M.toarray()
    kc = 92672.8044
    l, c = [0, 1, 2], [3]
    Kred = K[np.ix_(l, l)] - K[np.ix_(l, c)] @ K[np.ix_(c, l)] / K[3, 3]
    lam, phi = la.eigh(Kred, M[np.ix_(l, l)])
    phi_c = -(K[np.ix_(c, l)] @ phi)[0] / K[3, 3]
    static = np.linalg.inv(K)[3, 3]
    w = np.sqrt(lam)
    for H in (1, 3, 31):
        low = w <= (H + 1) * w[0] * (1 + 1e-12)
        expected = 1.0 / (static - np.sum(phi_c[low] ** 2 / lam[low]))
        r = MMSHBMProblem(model, H, r="residual").r_each[0]
        assert r == pytest.approx(expected, rel=1e-7), H  # cancellation ~1100x, as above
    # every mode below the cut: the node's spring alone
    H_all = int(np.ceil(w[-1] / w[0]))
    assert MMSHBMProblem(model, H_all - 2, r="residual").r_each[0] < kc * (1 - 1e-7)
    assert MMSHBMProblem(model, H_all, r="residual").r_each[0] == pytest.approx(kc, rel=1e-7)


@pytest.mark.parametrize("model, factor", [
    (one_mass(2.0027, 38.071, 33749.83), 10),   # default 9.0e-3, residual 5.0e-4 at H = 31
    (three_masses(), 10),                        # default 1.0e-2, residual 7.4e-4
])
def test_residual_r_cuts_the_truncation_error_against_the_exact_orbit(model, factor):
    """At 1.3 gaps and H = 31 the default r is 1e-2 off the exact single-contact orbit (the
    contact lasts ~2 % of the period); r = "residual" is within the 1e-3 of the corpus
    comparison and more than ``factor`` times closer; both converge to the exact orbit."""
    A = 1.3 * model.gap
    orbit = exact.periodic_orbit(model, A)
    assert orbit.converged and orbit.n_contacts == 1
    f_exact = orbit.frequency

    def error(H, r):
        b = mmshbm.backbone(model, harmonics=H, max_amplitude=1.2 * A, r=r)
        assert b.status == "bound:amplitude"
        return abs(b.frequency_at(A) / f_exact - 1)

    e_static, e_residual = error(31, None), error(31, "residual")
    assert e_static > 3e-3
    assert e_residual < 1e-3
    assert e_residual < e_static / factor
    assert error(62, "residual") < e_residual / 5


def test_named_r_is_validated():
    model = one_mass(1.0, 1.0, 100.0)
    with pytest.raises(ValueError, match=r"one of \('static', 'residual'\)"):
        mmshbm.backbone(model, harmonics=5, r="dynamic")
    a = mmshbm.backbone(model, harmonics=5, max_amplitude=0.02, r="static")
    b = mmshbm.backbone(model, harmonics=5, max_amplitude=0.02)
    np.testing.assert_array_equal(a.frequency, b.frequency)


def test_forced_response_takes_the_residual_rule():
    """The damped problems (forced responses, EPMC) take the same rule with the first
    mode's frequency for ω_ref."""
    from mmshbm.methods.mms.proximal import residual_stiffness

    model = one_mass(1.0, 100.0, 1e5).with_damping(0.02)
    f1 = model.linear_frequencies(1)[0]
    fr = mmshbm.frequency_response(model, [0.5, 0.0], (0.8 * f1, 1.2 * f1), harmonics=9, r="residual")
    expected = residual_stiffness(model, fr.solver.cond.D0, fr.solver.contact_rows, 9)
    np.testing.assert_allclose(fr.solver.r, expected, rtol=1e-12)
    assert fr.solver.r[0] == pytest.approx(1e5, rel=1e-7)  # cancellation ~1000x


def test_the_command_line_takes_the_rule(tmp_path, capsys):
    """``mmshbm backbone --proximal residual`` runs MMS-HBM with r = "residual": the saved
    branch says so and its solver, rebuilt from the file, has the residual stiffness."""
    from mmshbm.cli import main
    from mmshbm.io import load

    argv = ["backbone", "--elements", "4", "-H", "3", "--max-amplitude", "3", "--proximal", "residual"]
    assert main([*argv, "--out", str(tmp_path)]) == 0
    branch = load(tmp_path / "backbone.npz")
    assert branch.metadata["method_options"]["r"] == "residual"
    solver = branch._require_solver()
    static = MMSHBMProblem(branch.get_model(), 3)
    assert solver.r_each[0] > 5 * static.r_each[0]
