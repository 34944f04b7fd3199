"""A chain's first-mode orbit above a 2:1 tongue, which the jumps now reach.

Where a chain's backbone meets harmonic 2 of its second mode (2Ω = f₂), the orbit
continued from grazing becomes the second mode's orbit traversed twice; the first mode's
family goes on above the tongue, on orbits that keep the fundamental's majority and whose
fundamental is mostly linear mode 1 (`mmshbm.exact`, continued in amplitude: the modal
content of mode 1 in the fundamental 0.7–0.98). They lie far above the one-DOF zero-gap
limit 2/(1/f_open + 1/f_held) (17–31 % at 10 gaps) and below the frequency with the
contact DOF held. That limit refused the harmonic ladder's landings on them; and on
chains whose H = 3 family sits on the tongue's side up to the bound, the ladder from it
found none. Each case: the exact orbit at 10 gaps (Newton from open modes 1 and 2 mixed,
with a half period near the held frequency's), the default branch reaching 10 gaps, its
error against the exact orbit told by its own truncation estimate, and a run with more
harmonics closing in on the orbit.
"""

import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm import exact
from validation import corpus

#: (seed, index, H, a larger H, mode-2 mix of the guess, guess frequency (Hz), exact
#: frequency at 10 gaps (Hz), contacts per period)
CASES = {
    # two masses, a stiff node (4.46e6 N/m): open 11.15 / 23.08 Hz, held 21.96 Hz; the
    # ladder's landing (17.27 Hz) lay above the one-DOF limit 14.79 Hz
    "2-mass chain": (26, 130, 9, 19, -0.75, 21.975, 19.4272671502, 1),
    # seven masses: open 0.0934 / 0.1931 Hz, held 0.1793 Hz; the landing at 3.70 gaps
    # (0.1299 Hz) lay above the one-DOF limit 0.1228 Hz
    "7-mass chain": (11, 96, 9, 19, -0.5, 0.132, 0.143704301889, 2),
    # four masses: open 0.726 / 1.575 Hz, held 1.569 Hz; the H = 3 family sits on the
    # tongue's side (0.787 Hz = f₂/2) up to 10 gaps, the fundamental's (H = 1) does not
    "4-mass chain": (31, 272, 15, 31, -1.0, 1.44, 1.29398608676, 1),
}


def _kinetic_shares(model, orbit, n=4096):
    """(fundamental's share of the kinetic energy, linear mode 1's share of the
    fundamental's) of an exact orbit, from velocities at n instants."""
    M = np.asarray(model.M.toarray() if hasattr(model.M, "toarray") else model.M)[np.ix_(model.l, model.l)]
    t = np.linspace(0.0, orbit.period, n, endpoint=False)
    _, v = orbit.trajectory.state_l(t)
    V = np.fft.rfft(v, axis=1) / n
    e = np.einsum("ik,ij,jk->k", V.conj(), M, V).real[1:]
    _, phi = model.linear_modes(min(len(model.l), 4))
    modal = np.abs(phi[model.l].T @ M @ V[:, 1]) ** 2
    return e[0] / e.sum(), modal[0] / modal.sum()


def _exact_first_mode(model, mix, f_guess):
    """The exact orbit at 10 gaps from open mode 1 plus ``mix`` times mode 2 (scaled to
    mode 1's largest entry), the half period 0.5 / f_guess."""
    _, phi = model.linear_modes(2)
    phi = phi[model.l]
    x = phi[:, 0] + mix * phi[:, 1] * np.abs(phi[:, 0]).max() / np.abs(phi[:, 1]).max()
    try:
        return exact.periodic_orbit(model, 10 * model.gap, guess=(x, 0.5 / f_guess))
    except ValueError:  # the guess swung towards the stop: its mirror image
        return exact.periodic_orbit(model, 10 * model.gap, guess=(-x, 0.5 / f_guess))


@pytest.fixture(scope="module", params=sorted(CASES))
def case(request):
    seed, index, H, H_hi, mix, f_guess, f_exact, contacts = CASES[request.param]
    model = corpus.generate(index + 1, seed)[index].model()
    return model, (H, H_hi), _exact_first_mode(model, mix, f_guess), f_exact, contacts


def test_the_exact_first_mode_orbit_lies_above_the_one_dof_limit(case):
    model, _, orbit, f_exact, contacts = case
    assert orbit.converged and orbit.n_contacts == contacts
    assert orbit.max_excursion == pytest.approx(10 * model.gap, rel=1e-9)  # the clean symmetric orbit
    share, mode_1 = _kinetic_shares(model, orbit)
    assert share > 0.55 and mode_1 > 0.7
    assert orbit.frequency == pytest.approx(f_exact, rel=1e-9)
    assert orbit.frequency > 1.15 * model.zero_gap_frequency()


def test_the_default_reaches_the_bound_on_that_orbit(case):
    model, (H, H_hi), orbit, _, _ = case
    g = model.gap
    f_exact = orbit.frequency
    runs = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for h in (H, H_hi):
            runs[h] = mmshbm.backbone(model, harmonics=h, max_amplitude=10 * g)
            assert runs[h].status == "bound:amplitude", (h, runs[h].status)
    err = {h: abs(b.frequency_at(10 * g) / f_exact - 1) for h, b in runs.items()}
    # the stiff stops leave H harmonics 1-5 % off the exact orbit; more harmonics close in
    assert err[H] < 0.05 and err[H_hi] < err[H]
    est = runs[H].truncation_error(10 * g)
    if np.isfinite(est.error):  # the branch's own estimate (re-solves at 2H, 4H) tells the error
        assert 0.5 < est.error / err[H] < 2.0
