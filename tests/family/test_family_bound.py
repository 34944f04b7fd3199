"""Branches near their amplitude bound: a family the search finds between a loop and the
bound, and a branch of another mode above the bound that is not the family."""

import warnings

import numpy as np

import mmshbm


def _chain_clearance():
    """Two masses (13.19 and 6.06 kg; 25.7 N/m to the ground, 143.9 N/m between them)
    and a massless contact node on the second through 188.4 N/m, held by a clearance of
    ±1.052 mm (corpus seed 11, index 162)."""
    m0, m1 = 13.194469974422018, 6.060209325732203
    k0, k1, kc = 25.71047189101238, 143.93540716081057, 188.3655656087905
    M = np.diag([m0, m1, 0.0])
    K = np.array([[k0 + k1, -k1, 0.0], [-k1, k1 + kc, -kc], [0.0, -kc, kc]])
    gap = 0.0010523912122768968
    return mmshbm.Model.from_matrices(M, K, [2, 2], [gap, gap], [1, -1])


def test_the_family_found_above_the_bound_comes_down_onto_it():
    """At H = 3 the branch loops back at 8.53 gaps. The family goes on beyond: a run with
    its bound at 12 gaps passes 10 gaps on it. The search lands between the loop and the
    bound, the backfill reaches the frontier (nothing skipped), and the run reaches 10
    gaps on the 12-gap run's orbit (its point at 10 gaps, solved by ``frequency_at``: the
    same to 1e-9)."""
    model = _chain_clearance()
    gap = model.gap
    b = mmshbm.backbone(model, harmonics=3, max_amplitude=10 * gap)
    assert b.status == "bound:amplitude" and b.records["on_family"][-1] == 1.0
    jumps = [s for s in b.special_points if s.kind == "jump"]
    assert jumps and jumps[-1].data["landing_amplitude"] <= 10 * gap * (1 + 1e-9)
    assert jumps[-1].data["amplitude_to"] <= jumps[-1].data["amplitude_frontier"] * (1 + 1e-9)
    wider = mmshbm.backbone(model, harmonics=3, max_amplitude=12 * gap)
    assert wider.status == "bound:amplitude"
    assert abs(b.frequency[-1] / wider.frequency_at(10 * gap) - 1) < 1e-9


def test_a_branch_found_above_the_bound_on_another_mode_is_not_taken_for_the_family():
    """A 7-mass chain with two stops (corpus seed 14, index 103; H = 3): mode 1's backbone
    rises from 0.0404 Hz to 0.0549 Hz at 3.75 gaps, where harmonic 3 takes the majority
    and no jump lands below the bound. Above the bound (14.6 gaps) an orbit with the
    fundamental's majority lies at 0.1415 Hz, and its branch comes down onto the bound at
    0.1387 Hz: linear mode 2's (0.1089 Hz open), which holds 88 % of the kinetic energy
    there, in the fundamental, against mode 1's 0.6 % (the modal decomposition of the
    orbit, not the family test). The run must not follow it down as mode 1's backbone:
    every point it keeps on the family has mode 1 ahead of every other linear mode in the
    fundamental, and it ends short of the bound saying why."""
    from validation import corpus

    case = corpus.generate(104, seed=14)[103]
    model = case.model()
    b = mmshbm.backbone(model, harmonics=case.harmonics, max_amplitude=10 * model.gap)
    assert not b.completed and b.status.startswith("jump failed")
    on = np.asarray(b.records["on_family"]) == 1.0
    fundamental = np.asarray(b.records["modal_shares"])[:, :, 1]  # (points, linear modes)
    assert np.all(fundamental[on, 0] > fundamental[on, 1:].max(axis=1))
    assert np.isnan(b.frequency_at(5 * model.gap))


def _chain_locked_at_bound():
    """Two masses (96.12 and 3.554 kg; 24216 N/m to the ground, 71.65 N/m between them)
    and a massless contact node on the second through 32745 N/m, a stop 1 cm away
    (corpus_exact seed 32 with contact springs over 10¹–10⁵ N/m, chain 227): linear
    frequencies 0.7135 and 2.530 Hz, so the backbone crosses 3Ω = f₂ just above grazing."""
    m0, m1 = 96.12039440141906, 3.553771858702108
    k0, k1, kc = 24215.72436481033, 71.65004920227263, 32744.803183011758
    M = np.diag([m0, m1, 0.0])
    K = np.array([[k0 + k1, -k1, 0.0], [-k1, k1 + kc, -kc], [0.0, -kc, kc]])
    return mmshbm.Model.from_matrices(M, K, 2, 0.01, 1)


def test_a_climb_locked_onto_a_resonance_that_the_bound_cuts_short_is_a_tongue():
    """At H = 31 the branch turns at 1.19 gaps into the 3:1 tongue of the second mode: its
    frequency stays at f₂/3 = 0.84339 Hz while the amplitude rises, and the fundamental's
    share falls to 4e-4, but the stretch counted as pending (still advancing) until it
    grows by 1.5×. With the bound at 1.56 gaps it ended there "complete", and
    ``frequency_at(1.3 gaps)`` gave the tongue's 0.84338 Hz, 5 % below the exact
    first-mode orbit (0.889798 Hz, one contact per period), while a run to 10 gaps
    jumped the tongue and gave 0.88519 Hz. The climb locked at the bound is a tongue: the
    run jumps from below it, the answer at 1.3 gaps no longer depends on the bound, and
    it is the first mode's orbit within the truncation error at H = 31 (5.2e-3; 7.6e-5
    with r="residual", whose series is cut in the smooth variable)."""
    from mmshbm import exact

    model = _chain_locked_at_bound()
    gap = model.gap
    A = 1.3 * gap
    orbit = exact.periodic_orbit(model, A)
    assert orbit.converged and orbit.n_contacts == 1
    short = mmshbm.backbone(model, harmonics=31, max_amplitude=1.56 * gap)
    assert short.status == "bound:amplitude"
    assert [s for s in short.special_points if s.kind == "jump"]
    assert short.records["on_family"][-1] == 1.0
    assert abs(short.frequency[-1] - 0.84339) > 0.05  # the run does not end on the tongue
    wide = mmshbm.backbone(model, harmonics=31, max_amplitude=10 * gap)
    assert abs(short.frequency_at(A) / wide.frequency_at(A) - 1) < 1e-8
    assert abs(short.frequency_at(A) / orbit.frequency - 1) < 6e-3
    residual = mmshbm.backbone(model, harmonics=31, max_amplitude=1.56 * gap, r="residual")
    assert abs(residual.frequency_at(A) / orbit.frequency - 1) < 2e-4


def test_plain_path_following_onto_that_climb_is_told_it_left_the_family():
    """The same chain followed plainly to 1.56 gaps ends on the tongue's climb: the
    replayed guard judges the pending stretch at the bound as the family follower does,
    so the branch says it left the first mode's family (a "left_family" finding from
    the point where the fundamental lost the majority, 1.19 gaps), as a run continued
    past the tongue's lock would have said."""
    model = _chain_locked_at_bound()
    gap = model.gap
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        path = mmshbm.backbone(model, harmonics=31, max_amplitude=1.56 * gap, follow="path")
    assert path.status == "bound:amplitude"
    left = [f for f in path.metadata["checks"] if f["kind"] == "left_family"]
    assert left and 1.15 < path.amplitude[left[0]["first"]] / gap < 1.2
