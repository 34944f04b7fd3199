"""The per-point bookkeeping kept per model (fingerprint, held frequency, energy-share basis,
recovery blocks) and the recovery-free signals of massless DOFs give what the direct
computations give."""

import dataclasses

import numpy as np

import mmshbm
from mmshbm.methods.mms import held
from mmshbm.methods.registry import make_problem


def _problem(model, **kw):
    return make_problem(model, "mmshbm", harmonics=5, **kw)


def test_signals_of_massless_dofs_need_no_recovery():
    model = mmshbm.default_beam().model(21)
    p = _problem(model)
    u = p.linear_point(1.5 * model.gap)
    dofs = np.array([model.c[-1], model.c[0], model.l[3]])
    t, q_all = p.time_signals(u, n_samples=64)
    for sel in (dofs[:2], dofs, np.array([-1])):
        t_s, q = p.time_signals(u, dofs=sel, n_samples=64)
        np.testing.assert_array_equal(t_s, t)
        np.testing.assert_allclose(q, q_all[sel], rtol=0, atol=1e-15 * np.abs(q_all).max())


def test_kept_values_equal_fresh_ones():
    model = mmshbm.default_beam().model(21)
    first = model.fingerprint()
    assert model.fingerprint() is first
    same = dataclasses.replace(model)  # a new object: its own computation
    assert same.fingerprint() == first and "_memo_fingerprint" not in dataclasses.replace(model).__dict__
    assert model.with_gap(2e-3).fingerprint() != first
    dofs = tuple(c.dof for c in model.contacts)
    kept = held._held_frequency(model, dofs, 1)
    assert kept == held._held_frequency_solve(model, dofs, 1)
    a, b = _problem(model), _problem(model)
    assert a._modal_basis() is b._modal_basis()
    assert a.tracked_frequencies is not a._modal_basis()[0]
    u = a.linear_point(1.2 * model.gap)
    np.testing.assert_array_equal(a.modal_shares(u), b.modal_shares(u))
