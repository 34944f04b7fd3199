"""The records of the friction forced response: the coefficients of the DOFs with mass by one
batched solve with S_k (FrictionForcedProblem._coefficients, where the dense blocks are held)
against the condensation's recovery (ForcedResponseProblem._coefficients), and the energy with
dense K, M against mmshbm.core.measures.mean_energy.

The two recoveries solve the same linear systems S_k Q̂_l,k = σ F̂_l δ_k1 − K_lc Q̂_c,k by two
backward-stable routes (LU of S_k; the modal form of the condensation), so they differ by at
most c·n·ε·κ(S_k)·|Q̂_l,k| (Higham, §7.1), κ the 2-norm condition number of S_k; a wrong sign,
harmonic or index changes Q by the size of a term. The energy is the same sums of products in
another order: within the round-off of its terms (tests/roundoff.py)."""

import numpy as np
import pytest
from roundoff import assert_roundoff_close

import mmshbm
from mmshbm.core.measures import mean_energy
from mmshbm.fe.euler_bernoulli import cantilever
from mmshbm.methods.mms.forced import ForcedResponseProblem
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

EPS = np.finfo(float).eps


def _beam(kt):
    """NLvib's example-08 beam (8 elements), μN = 1.5 N at node 4 behind k_t, 0.2 N at the tip."""
    M, K, dofs = cantilever(2.0, 0.3, 0.1, 185e9, 7830.0, 8)
    node4, tip = int(dofs[3, 0]), int(dofs[-1, 0])
    C = 1e-4 * K.toarray()
    model = mmshbm.Model.from_matrices(M, K, [], [], [], damping=C, amplitude_dof=tip)
    model = model.with_friction(node4, 1.0, normal_load=1.5, tangential_stiffness=kt)
    force = np.zeros(model.n_dof)
    force[tip] = 0.2
    return model, force


def _oscillator():
    M = np.diag([1.0, 0.0])
    K = np.array([[3.0, -2.0], [-2.0, 2.0]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([0.05, 0.0]), amplitude_dof=0)
    return base.with_friction(1, 0.5, normal_load=0.2), [0.1, 0.0]


@pytest.mark.parametrize("case, frequencies", [
    ("beam", (18.0, 20.5, 21.2, 23.0)),  # stuck, slip onset, slipping near the peak, above it
    ("oscillator", (0.12, 0.2, 0.3)),
])
def test_batched_recovery_is_the_condensation_recovery(case, frequencies):
    model, force = _beam(1e7) if case == "beam" else _oscillator()
    p = FrictionForcedProblem(model, force, 13)
    tr = p._tracker
    assert tr is not None  # the amplitude DOF carries mass: the dense blocks are held
    slipping = 0
    for f in frequencies:
        u = p.start_point(f)
        x, omega = p.unpack(u)
        slipping += p.monitor(u)["slip_fraction"] > 0
        Q = p._coefficients(x, omega, 1.0)
        p._cache = None
        Q_ref = ForcedResponseProblem._coefficients(p, x, omega, 1.0)
        l = model.l
        np.testing.assert_array_equal(Q[model.c], Q_ref[model.c])  # copied, not computed
        for k in range(p.H + 1):
            w = k * omega
            S = tr.K_ll + 1j * w * tr.C_ll - w**2 * tr.M_ll
            cols = [0] if k == 0 else [2 * k - 1, 2 * k]
            size = np.abs(Q_ref[np.ix_(l, cols)]).max()
            tol = 16 * len(l) * EPS * np.linalg.cond(S) * size + 1e-300
            err = np.abs(Q[np.ix_(l, cols)] - Q_ref[np.ix_(l, cols)]).max()
            assert err <= tol, f"{f} Hz, harmonic {k}: {err:.3g} > {tol:.3g}"
        E = p._energy(Q, omega)
        E_ref = mean_energy(model, Q, omega)
        A = np.abs(Q)
        scale = (np.einsum("ij,ij->", A, np.abs(model.K.toarray()) @ A)
                 + omega**2 * p.H**2 * np.einsum("ij,ij->", A, np.abs(model.M.toarray()) @ A))
        assert_roundoff_close(E, E_ref, scale, terms=4 * model.n_dof * (2 * p.H + 1))
    assert slipping >= 2  # the comparison covers slipping orbits, not only the linear stuck one


def test_records_are_those_of_the_unfused_path():
    """The fused _record (the needed force once; one compiled call where the evaluation is
    fused, :mod:`mmshbm.methods.mms.friction_fused`) against the forced record and
    friction_records, to round-off: the coefficients are solves with S_k in both (within
    κ(S_k)·ε of each other), the energy's sums differ (dense against sparse products), the
    friction work is a Parseval sum of 2H terms of |F_k| k |x_k|, the slip fraction's
    switching instants are refined to round-off."""
    model, force = _beam(1e7)
    p = FrictionForcedProblem(model, force, 13)
    u = p.start_point(21.2)
    x, omega = p.unpack(u)
    rec = p.monitor(u)
    ref = ForcedResponseProblem._record(p, x, omega, 1.0)
    ref.update(p.friction_records(x, omega, 1.0))
    assert rec.keys() == ref.keys()
    assert rec["slip_fraction"] > 0
    eps = np.finfo(float).eps
    tr = p._tracker
    cond = max(np.linalg.cond(tr.K_ll + 1j * k * omega * tr.C_ll - (k * omega) ** 2 * tr.M_ll)
               for k in range(p.H + 1))
    rel = 64 * cond * eps * p.n_coef
    F = p._needed(x, omega, 1.0)
    idx = p._coef_index[p.friction_rows[0]]
    k = np.repeat(np.arange(1, p.H + 1), 2)
    swapped = x[idx][1:].reshape(-1, 2)[:, ::-1].ravel()  # (s_k, c_k) against (F_c,k, F_s,k)
    work_terms = np.pi * np.sum(np.abs(F[idx][1:]) * k * np.abs(swapped))
    tols = {"frequency": 0.0, "amplitude": rel * abs(ref["amplitude"]), "phase": rel,
            "energy": 1e-13 * abs(ref["energy"]), "contact_force_max": 0.0, "slip_fraction": 1e3 * eps,
            "friction_dissipation": 8 * p.n_coef * eps * work_terms}
    for key in ref:
        assert abs(rec[key] - ref[key]) <= tols[key], key
