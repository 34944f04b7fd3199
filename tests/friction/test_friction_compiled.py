"""The compiled friction evaluation against its NumPy reference, to round-off: the play
projection kernel, the fused residual and Jacobian of the friction forced response (friction
rows alone and with a unilateral stop), and the tracked harmonic of the amplitude DOF.

Two code paths of one computation differ by their round-off only (tests/roundoff.py). The
play projection's switching instants are zeros refined to round-off by both paths; g is
continuous at every switch, so an instant off by δτ moves g by O(δτ²) and the Jacobian (through
φ(τ_e), τ_e an extremum of y) by r·H·δτ: on the well-separated extrema of these signals
(|y″| of the order of Σ k²|c_k| there) δτ is a few ulps, inside the tolerance's terms."""

import numpy as np
import pytest
from roundoff import assert_roundoff_close, product_scale

import mmshbm
from mmshbm.contact.coulomb import _project_play_numpy, project_coulomb_play
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
from mmshbm.methods.mms.friction_tracked import TrackedHarmonic


def _signal(H, seed, mean=0.1):
    """A harmonic-1-dominated y: its extrema are simple (|y″| ~ amplitude there)."""
    rng = np.random.default_rng(seed)
    y = np.concatenate([[mean], rng.normal(size=2 * H) / np.repeat(np.arange(1, H + 1) ** 2, 2)])
    y[1:3] += 2.0 * np.sign(y[1:3])
    return y


@pytest.mark.parametrize("H", [1, 4, 7, 15])
@pytest.mark.parametrize("s", [0.0, 0.3, 1.5, 50.0])  # free, slipping, near full stick, full stick
def test_play_kernel_is_the_numpy_projection(H, s):
    n = 2 * H + 1
    for seed in range(6):
        y = _signal(H, seed)
        r = 0.7 + 0.5 * seed
        g, J, slip = project_coulomb_play(y, s, r)
        g0, J0, slip0 = _project_play_numpy(y, s, r)
        g1, none, slip1 = project_coulomb_play(y, s, r, jacobian=False)
        assert none is None
        scale_g = s + r * np.abs(y).sum()
        assert_roundoff_close(g, g0, scale_g, terms=4 * n, err_msg=f"g, seed {seed}")
        assert_roundoff_close(g1, g0, scale_g, terms=4 * n, err_msg=f"g without J, seed {seed}")
        assert_roundoff_close(J, J0, 4 * r, terms=4 * n, err_msg=f"J, seed {seed}")
        assert_roundoff_close(slip, slip0, 1.0, terms=8, err_msg=f"slip, seed {seed}")
        assert slip == slip1
        if s == 50.0:  # sticks throughout at the symmetric position
            assert slip == 0.0


def _two_mass_damper():
    M = np.diag([1.0, 1.0])
    K = np.array([[2e4, -1e4], [-1e4, 1e4]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], amplitude_dof=1).with_damping(modal_ratio=0.01)
    return base.with_friction(1, 0.5, normal_load=10.0, tangential_stiffness=1e4), [10.0, 0.0, 0.0]


def _stop_and_friction():
    """Two masses driving a node's normal DOF (a stop 0.05 m away) and tangential DOF
    (friction with a constant load)."""
    M = np.diag([1.0, 1.0, 0.0, 0.0])
    K = np.array([[5.5, -0.5, -4, 0], [-0.5, 3.5, 0, -2], [-4, 0, 4, 0], [0, -2, 0, 2]], float)
    base = mmshbm.Model.from_matrices(M, K, [2], [0.05], [+1], damping=np.diag([0.05, 0.05, 0.0, 0.0]),
                                      amplitude_dof=0)
    return base.with_friction(3, 0.3, normal_load=0.05), [0.1, 0.1, 0.0, 0.0]


def _parts(p, omega):
    ch = p._condensed(omega, 0.0, True)
    s, ds = p.excitation.scale(omega)
    Pv = p.first_harmonic_vector(s * ch.P[:, 0])
    dD = np.zeros((2,) + ch.D.shape, dtype=complex)
    dD[0] = ch.dD_domega
    dload = np.column_stack([p.first_harmonic_vector(s * ch.dP_domega[:, 0] + ds * ch.P[:, 0]), Pv])
    return ch.D, Pv, dD, dload


@pytest.mark.parametrize("case,ratios", [(_two_mass_damper, (0.6, 0.95, 1.0, 1.3, 1.9)),
                                         (_stop_and_friction, (0.5, 0.9, 1.0, 1.2))])
def test_fused_friction_residual_is_the_numpy_one(case, ratios):
    """At converged orbits and at perturbed iterates (other stick-slip patterns), residual
    and Jacobian of the compiled rows against the NumPy rows (:meth:`residual_from_blocks`
    with ``_compiled_rows`` off). Scale of a row:
    the terms |𝔇||x| + |load| of F, and on a friction row those of g (s + ρ Σ|y|); of a
    Jacobian entry (1 + ‖J_g‖/ρ) times the largest entry of 𝔇 and its Ω derivative, plus
    ‖J_g‖ (‖J_g‖ <= 4ρ: the indicator spectra are at most 2 and φ at most 1)."""
    model, force = case()
    p = FrictionForcedProblem(model, force, 7)
    assert p._compiled_rows
    f1 = p.linear_frequency
    rng = np.random.default_rng(3)
    for ratio in ratios:
        u = p.start_point(ratio * f1)
        x0, omega = p.unpack(u)
        D, load, dD, dload = _parts(p, omega)
        Dx, dDx = p.real_blocks(D), p.real_blocks(dD[0])
        for x in (x0, 1.5 * x0 + 0.05 * np.abs(x0).max() * rng.normal(size=x0.shape)):
            R, Jx, Jp = p.fused_residual(D, x, load, dD, dload)
            R_only = p.fused_residual(D, x, load)[0]
            p._compiled_rows = False  # the NumPy rows (FrictionRows.friction_law)
            try:
                R0, Jx0, Jp0 = p.residual_from_blocks(D, x, load, dD, dload)
            finally:
                p._compiled_rows = True
            scale = product_scale(Dx, x) + np.abs(load)
            for j, i in enumerate(p.friction_rows):
                idx = p._coef_index[i]
                y_terms = np.abs(x[idx]).sum() + scale[idx].sum() / p.rho[j]  # Σ|y|, y = x_t − F_t/ρ
                scale[idx] += p.slip_force[j] + p.rho[j] * y_terms
            terms = p.n_x + 8 * p.n_coef
            assert_roundoff_close(R, R0, scale, terms, err_msg=f"R at {ratio} f1")
            assert_roundoff_close(R_only, R0, scale, terms, err_msg=f"R alone at {ratio} f1")
            rho = float(np.max(p.rho))
            jscale = 5.0 * max(np.abs(Dx).max(), rho) * p.n_coef
            assert_roundoff_close(Jx, Jx0, jscale, terms, err_msg=f"dR/dx at {ratio} f1")
            pscale = 5.0 * (product_scale(dDx, x).max() + np.abs(dload).max()) * p.n_coef
            assert_roundoff_close(Jp, Jp0, pscale, terms, err_msg=f"dR/dparams at {ratio} f1")


def test_tracked_harmonic_is_the_explicit_inverse():
    """z, y and their Ω derivatives against S⁻¹ formed explicitly and ∂S⁻¹ = −S⁻¹S′S⁻¹
    (a different factorisation and order): both within cond(S)·ε of the exact values."""
    from mmshbm.fe.euler_bernoulli import cantilever

    M, K, dofs = cantilever(2.0, 0.3, 0.1, 185e9, 7830.0, 8)
    C = 1e-4 * K
    node4, tip = int(dofs[3, 0]), int(dofs[-1, 0])
    model = mmshbm.Model.from_matrices(M, K, [], [], [], damping=C, amplitude_dof=tip)
    model = model.with_friction(node4, 1.0, normal_load=1.5, tangential_stiffness=1e7)
    b = model.blocks
    Kll, Mll, Cll, Klc = (A.toarray() if hasattr(A, "toarray") else np.asarray(A)
                          for A in (b["K_ll"], b["M_ll"], b["C_ll"], b["K_lc"]))
    rng = np.random.default_rng(0)
    fl = rng.normal(size=Kll.shape[0]) + 1j * rng.normal(size=Kll.shape[0])
    for row in (0, Kll.shape[0] // 2, Kll.shape[0] - 1):
        tr = TrackedHarmonic(b, row, fl)
        for omega in (40.0, 300.0, 2500.0):
            z, y, dz, dy = tr.at(omega, derivative=True)
            S = Kll + 1j * omega * Cll - omega**2 * Mll
            Si = np.linalg.inv(S)
            dSi = -Si @ (1j * Cll - 2 * omega * Mll) @ Si
            cond = np.linalg.cond(S)
            refs = (Si[row] @ Klc, Si[row] @ fl, dSi[row] @ Klc, dSi[row] @ fl)
            for got, ref in zip((z, y, dz, dy), refs, strict=True):
                got, ref = np.atleast_1d(got), np.atleast_1d(ref)
                tol = 64 * cond * np.finfo(float).eps * np.abs(ref).max()
                assert np.abs(got - ref).max() <= tol, (row, omega, np.abs(got - ref).max(), tol)
            z2 = tr.at(omega)[0]  # the memo, same numbers
            assert np.array_equal(z2, z)


def test_friction_epmc_evaluates_the_compiled_rows_as_the_numpy_ones():
    """The EPMC's scaled residual and Jacobian (the friction rows through
    :meth:`contact_residual`) with the compiled rows against the NumPy rows, on the Jenkins
    oscillator pinned at growing amplitudes (stuck, then slipping). Scaled rows and columns
    are O(1) with terms up to ~1e2 (the harmonic-1 rows of the mass), 2H+1 of them summed."""
    from mmshbm.methods.mms.friction_epmc import FrictionEPMCProblem

    M = np.diag([1.0, 0.0])
    K = np.array([[3.0, -2.0], [-2.0, 2.0]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([0.05, 0.0]), amplitude_dof=0)
    p = FrictionEPMCProblem(base.with_friction(1, 0.5, normal_load=0.2), 7)
    assert p._compiled_rows
    col = p.n_x + p.amp_l
    u = p.linear_point(0.04)
    checked = 0
    for a in np.linspace(0.04, 0.3, 12):
        for _ in range(40):  # Newton with the amplitude pinned
            R, J = p.evaluate(u)
            r = np.append(R, u[col] - a / p.colscale[col])
            if np.abs(r).max() < 1e-12:
                break
            u = u - np.linalg.solve(np.vstack([J, np.eye(len(u))[col]]), r)
        R, J = p.evaluate(u)
        R_only = p.evaluate(u, False)
        p._compiled_rows = False
        try:
            R0, J0 = p.evaluate(u)
        finally:
            p._compiled_rows = True
        scale = 1e2 * (1.0 + np.abs(u).max())
        terms = 8 * p.n_coef
        assert_roundoff_close(R, R0, scale, terms, err_msg=f"R at {a}")
        assert_roundoff_close(R_only, R0, scale, terms, err_msg=f"R alone at {a}")
        assert_roundoff_close(J, J0, scale, terms, err_msg=f"J at {a}")
        checked += 1
    assert checked == 12
    assert p.monitor(u)["slip_fraction"] > 0.1  # the last orbits slip


@pytest.mark.parametrize("H", [2, 7, 15])
def test_play_pieces_kernel_is_the_numpy_walk(H):
    """The stick and slip pieces (the Floquet solver's input) of the compiled walk against
    the NumPy extrema and walk: the same pattern, arcs and stick positions to round-off
    (zeros refined to a few ulps of 2π, positions sums of 2H+1 terms of |y|)."""
    from mmshbm.contact.coulomb import _play_arrays, play_pieces

    for seed in range(6):
        y = _signal(H, seed)
        for s in (0.0, 0.4, 2.0, 50.0):
            pieces = play_pieces(y, s, 1.3)
            a, b, sg, u, te = _play_arrays(y, s, 1.3)
            assert [p[2] for p in pieces] == [int(v) for v in sg], (seed, s)
            got = np.array([[p[0], p[1], p[3], p[4]] for p in pieces])
            ref = np.column_stack([a, b, u, te])
            scale = np.array([2 * np.pi, 2 * np.pi, np.abs(y).sum() + s / 1.3, 2 * np.pi])
            assert_roundoff_close(got, ref, scale[None, :], terms=4 * len(y), err_msg=f"seed {seed}, s {s}")
