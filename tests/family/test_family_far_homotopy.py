"""Branches that turn back in amplitude: the family found farther up, checked against the
exact orbit, and a landing apart from the family below."""

import warnings

import numpy as np

import mmshbm
from mmshbm.methods import exact as ex
from validation import corpus


def _fundamental_share(model, orbit, n=4096):
    """Share of the fundamental in the kinetic energy of an exact orbit (FFT of the
    closed-form velocities of the DOFs with mass)."""
    M = np.asarray(model.M.toarray() if hasattr(model.M, "toarray") else model.M)[np.ix_(model.l, model.l)]
    t = np.linspace(0.0, orbit.period, n, endpoint=False)
    _, v = orbit.trajectory.state_l(t)
    V = np.fft.rfft(v, axis=1) / n
    e = np.einsum("ik,ij,jk->k", V.conj(), M, V).real
    return e[1] / e[1:].sum()


def test_a_light_host_rattling_reaches_its_bound_on_an_exact_orbit():
    """4-mass chain, the stop on a 0.42 kg mass weakly coupled to a 33 kg one (corpus seed
    27 index 105, H = 15): the branch turns back at 3.62 gaps; the search lands beyond
    it, and the family, filled back down, rises to 10 gaps. There the exact
    orbit (closed-form phases, `mmshbm.exact`, Newton from the branch's orbit) closes the
    contact four times per period, keeps the fundamental's majority and lies within
    1e-3 of the branch's frequency (the truncation at H = 15 of a rattling host); a run
    to 15 gaps gives the same frequency at 10 gaps."""
    case = corpus.generate(106, 27)[105]
    model = case.model()
    gap = model.gap
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        b = mmshbm.backbone(model, harmonics=15, max_amplitude=10 * gap)
        longer = mmshbm.backbone(model, harmonics=15, max_amplitude=15 * gap)
    assert b.status == "bound:amplitude" and b.completed
    jump = [s for s in b.special_points if s.kind == "jump"][-1]
    assert jump.data["landing_amplitude"] > jump.data["amplitude_frontier"]
    after = np.asarray(b.amplitude[jump.index:])
    assert np.all(np.diff(after) > 0) and abs(after[-1] / (10 * gap) - 1) < 1e-9
    f10 = b.frequency_at(10 * gap)
    # both refined onto 10 gaps by Newton to 1e-10 from points of different runs
    assert abs(longer.frequency_at(10 * gap) / f10 - 1) < 1e-8
    Q = b.solver.coefficients(b.states[-1])
    far = Q[:, 0] + Q[:, 1::2] @ (-1.0) ** np.arange(1, b.harmonics + 1)  # τ = π: away from the stop
    orbit = ex.periodic_orbit(model, float(b.amplitude[-1]), guess=(far[model.l], 0.5 / f10), max_iter=60)
    assert orbit.converged and orbit.n_contacts >= 2
    assert abs(orbit.max_excursion / b.amplitude[-1] - 1) < 1e-9
    assert abs(orbit.frequency / f10 - 1) < 1e-3
    assert _fundamental_share(model, orbit) > 0.5


def test_a_landing_apart_from_the_family_below_is_refused():
    """3-mass chain (corpus seed 36 index 58, H = 9) whose branch turns back at grazing:
    a homotopy at a spread target lands at 5.75 gaps on an orbit whose branch does not
    come back down to the frontier, and ends at 10 gaps at 0.164 Hz, where the runs at
    H = 5 and 15 (which pass grazing) give 0.184 and 0.192 Hz: another orbit. Such a
    landing is refused; the run may end short, but not on a branch 10 % away from its
    neighbours in H."""
    model = corpus.generate(59, 36)[58].model()
    gap = model.gap
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        b = mmshbm.backbone(model, harmonics=9, max_amplitude=10 * gap)
        finer = mmshbm.backbone(model, harmonics=15, max_amplitude=10 * gap)
    assert finer.completed and 0.18 < finer.frequency_at(10 * gap) < 0.2
    if b.completed:
        assert abs(b.frequency_at(10 * gap) / finer.frequency_at(10 * gap) - 1) < 0.05
    else:
        assert "does not come down" in b.status or "turns back" in b.status
