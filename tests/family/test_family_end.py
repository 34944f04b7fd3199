"""Where the starting mode's own orbit loses the fundamental's majority, the family ends,
and the run says so (status ``"family ended: ..."``), checked against the exact orbit."""


import numpy as np

import mmshbm
from mmshbm.core.status import Status


def _two_mass_chain():
    """Two masses in a chain (1.167 and 1.080 kg on 365.9 and 109.9 N/m) and a massless
    contact node on the second through a stiff spring (5.8e5 N/m), one stop at 0.194 mm
    (corpus seed 13, index 10). Open modes 1.3607 and 3.324 Hz."""
    m0, m1 = 1.167251569460881, 1.080052549456277
    k0, k1, kc = 365.88039617557155, 109.85778151462809, 581982.3631472578
    M = np.diag([m0, m1, 0.0])
    K = np.array([[k0 + k1, -k1, 0.0], [-k1, k1 + kc, -kc], [0.0, -kc, kc]])
    return mmshbm.Model.from_matrices(M, K, 2, 0.00019428500911325972, 1)


def _fundamental_share(model, orbit) -> float:
    """The fundamental's share of the period-mean kinetic energy of an exact orbit, from
    its velocities sampled at 2048 instants (harmonics 1..1024)."""
    M = np.asarray(model.blocks["M_ll"].toarray() if hasattr(model.blocks["M_ll"], "toarray")
                   else model.blocks["M_ll"])
    n = 2048
    V = np.array([orbit.trajectory.v(t)[model.l] for t in np.arange(n) * orbit.period / n])
    C = np.fft.rfft(V, axis=0) / n
    E = np.einsum("ki,ij,kj->k", C.conj(), M, C).real
    return float(E[1] / E[1:].sum())


def test_past_a_2_to_1_tongue_the_family_goes_on_along_its_far_side():
    """2Ω approaches the second mode (3.324 Hz) as the backbone stiffens towards 1.65 Hz:
    the exact orbit, continued from the linear mode, holds the fundamental's majority up
    to 1.5 gaps (share 0.513) and loses it from there on, its frequency locked below
    f2/2 (share 0.42 at 1.6 gaps, 0.13 at 2.5 gaps). The family goes on along the tongue's
    far side, 25-50 % higher in frequency: exact orbits with one contact per period and
    three quarters of the energy in the fundamental from 2.2 to 10 gaps (2.0989 Hz at 2.2
    gaps, 2.5032 Hz at 10, shot from the branch's points). No predictor from the branch
    below reaches them; the frequency scan of the jumps does (before: "family ended" at
    1.645 gaps). With r = "residual" the branch is 0.7-0.8 % below those exact orbits at
    H = 15 (the truncation); the default r, further (4 % at 3 gaps), converges toward
    them in H."""
    from validation.corpus_exact import branch_orbit

    model = _two_mass_chain()
    gap = model.gap
    steps = np.arange(0.9, 2.55, 0.1)
    ex = mmshbm.exact.backbone(model, gap * steps)
    assert ex.converged.all() and (ex.n_contacts[steps > 1.05] == 1).all()
    shares = np.array([_fundamental_share(model, o) for o in ex.orbits])
    lost = steps[shares < 0.5]
    # the continued exact orbit loses the majority between 1.5 and 1.6 gaps for good
    assert 1.5 < lost[0] < 1.65 and (shares[steps >= lost[0] - 1e-9] < 0.5).all()

    b = mmshbm.backbone(model, harmonics=15, max_amplitude=10 * gap, r="residual")
    assert b.status == "bound:amplitude", b.status
    assert any(s.kind == "jump" for s in b.special_points)
    for a in (2.2, 3.0, 5.0, 10.0):
        f_exact, share = branch_orbit(model, b, a * gap)
        assert share > 0.7, a
        assert f_exact > 1.25 * np.interp(min(a, 2.5), steps, ex.frequency)  # the far side
        assert abs(b.frequency_at(a * gap) / f_exact - 1) < 0.01, a  # measured 0.7-0.8 %
    f3 = branch_orbit(model, b, 3 * gap)[0]
    errors = []
    for H in (15, 31):
        default = mmshbm.backbone(model, harmonics=H, max_amplitude=10 * gap)
        assert default.status == "bound:amplitude", default.status
        errors.append(abs(default.frequency_at(3 * gap) / f3 - 1))
    assert errors[1] < errors[0] / 1.5 and errors[0] < 0.05  # measured 4.0 %, 1.8 %


def _tree_one_sided():
    """A 3-mass tree (17.05, 0.112 and 3.857 kg; 1114.5, 38.8 and 102.3 N/m in a line,
    the third mass also on 361.0 N/m to the ground) with a massless contact node on the
    third mass through 2.2e5 N/m and a stop at −0.337 mm (corpus seed 14, index 97).
    Open modes 1.2987, 1.5888, 5.685 Hz."""
    m = [17.0483925127443, 0.11246969655670268, 3.8567845183354326]
    k = [1114.5472227962791, 38.771770455930195, 102.31111267890847]
    kg, kc = 360.95225897429225, 220681.52590074207
    K = np.zeros((4, 4))
    for a, b, s in ((0, -1, k[0]), (1, 0, k[1]), (2, 1, k[2]), (2, -1, kg), (3, 2, kc)):
        K[a, a] += s
        if b >= 0:
            K[b, b] += s
            K[a, b] -= s
            K[b, a] -= s
    return mmshbm.Model.from_matrices(np.diag(m + [0.0]), K, 3, 0.0003367466016382903, -1)


def test_a_backbone_folded_by_its_truncation_resumes_on_the_exact_orbit():
    """At H = 15 the backbone rises from 1.2987 Hz to 1.30297 Hz and turns back in
    amplitude at 7.35 gaps with the fundamental's whole share (0.997): plain path following
    turns back there too and returns to the linear mode. The exact orbit (two contacts per
    period) goes on smoothly to 10 gaps between the two: the fold is the truncation's. The
    H = 15 orbits beyond it lie below the fold's frequency, on a piece of the family that
    begins at a fold of its own (7.77 gaps) and that no predictor taken from the branch
    below reaches; the search lands on it and the backfill follows it down to its fold.
    On it the branch agrees with the exact orbit as well as it did below the first fold."""
    from mmshbm.methods.exact import orbits

    model = _tree_one_sided()
    gap = model.gap
    b = mmshbm.backbone(model, harmonics=15, max_amplitude=10 * gap)
    assert b.status.kind == Status.BOUND and b.completed
    path = mmshbm.backbone(model, harmonics=15, max_amplitude=10 * gap, follow="path", max_steps=60)
    i = int(np.argmax(path.amplitude))
    assert 0 < i < len(path) - 1 and path.amplitude[-1] < path.amplitude[i]
    assert path.records["fundamental_share"][: i + 1].min() > 0.99
    fold, f_fold = float(path.amplitude[i]), float(path.frequency[i])
    jumps = [sp for sp in b.special_points if sp.kind == "jump"]
    assert len(jumps) == 1
    resumed = float(jumps[0].data["amplitude_to"])
    assert fold < resumed < 1.1 * fold  # the family's next piece begins just above the fold
    assert float(jumps[0].data["frequency_to"]) < f_fold  # below the fold's frequency

    def error(gaps):
        exact = orbits.periodic_orbit(model, gaps * gap)
        assert exact.converged
        return abs(b.frequency_at(gaps * gap) * exact.period - 1)

    below = max(error(g) for g in (2.0, 5.0, 7.0))  # the truncation's error below the fold
    assert below < 1e-3
    for g in (8.0, 9.0, 10.0):
        assert error(g) <= below


def _tree_clearance():
    """A 1.071 kg mass on 71.9 N/m to a 7.397 kg mass (6990 N/m to the ground, 10728 N/m
    to the ground beside it), a massless contact node on the light mass through 1.05e6
    N/m between stops at +1.099 mm and −0.919 mm (corpus seed 17, index 299)."""
    M = np.diag([1.0712918118682342, 7.397096416200371, 0.0])
    K = np.array([[1053511.1069382997, -6990.413371954646, -1046448.7777371964],
                  [-6990.413371954646, 17717.974448525834, 0.0],
                  [-1046448.7777371964, 0.0, 1046448.7777371964]])
    gaps = [0.001099011434298534, 0.0009185609204247609]
    return mmshbm.Model.from_matrices(M, K, contact_dof=[2, 2], gap=gaps, stop_side=[1, -1], amplitude_dof=1)


def test_a_backbone_that_turns_back_resumes_only_beyond_a_reported_skip():
    """At H = 15 the clearance's backbone turns back in amplitude at 2.36 gaps, 7.896 Hz,
    with the fundamental's share at 0.75 (no internal resonance took the energy); plain
    path following turns back at the same point. The run goes on only on a piece of the
    family found beyond the fold: the interval between is reported as skipped
    (``frequency_at`` NaN inside), and the points either side satisfy the definition."""
    model = _tree_clearance()
    bound = 10 * model.gap
    b = mmshbm.backbone(model, harmonics=15, max_amplitude=bound)
    assert b.status.kind == Status.BOUND, b.status
    first = [s for s in b.special_points if s.kind == "jump"][0]
    lo, hi = first.data["amplitude_frontier"], first.data["amplitude_to"]
    assert hi > 1.01 * lo
    assert np.isnan(b.frequency_at(0.5 * (lo + hi)))
    for A in (lo, hi):
        i = int(np.argmin(np.abs(b.amplitude - A)))
        assert b.records["fundamental_share"][i] >= 0.5
    top = int(first.data["from_index"])
    path = mmshbm.backbone(model, harmonics=15, max_amplitude=bound, follow="path", max_steps=120)
    i = int(np.argmax(path.amplitude))
    assert 0 < i < len(path) - 1 and path.amplitude[-1] < path.amplitude[i]
    # the turning point as sampled by either run: within the steps' resolution there
    assert abs(path.amplitude[i] / b.amplitude[top] - 1) < 1e-3
    assert abs(path.frequency[i] / b.frequency[top] - 1) < 1e-5
    assert path.records["fundamental_share"][: i + 1].min() > 0.5


def test_the_far_side_of_a_2_to_1_tongue_converges_to_the_exact_orbits():
    """Corpus seed 55 #180 (a chain of two masses and two light stiff ones, open modes
    2.811 and 6.339 Hz, a one-sided contact 2000 times stiffer than the structure): the
    backbone climbs a 2:1 tongue of mode 2 at 1.89 gaps (3.096 Hz), and the family goes on
    along the far side, exact from 1.02 gaps (3.537 Hz) to 10 gaps (4.804 Hz) with one
    contact per period and about 0.74 of the energy in the fundamental. With r =
    "residual" the run lands on it and follows it to 10 gaps at H = 15 and 31, within
    2e-3 and then 2e-5 of the exact orbits (measured 1.7e-3 and 1e-5: the truncation).
    The default r reaches it at H = 15 through the scan in frequency (before: "family
    ended" at 1.89 gaps), 2.0, 1.7 and 1.5 % below it at 2.2, 5 and 10 gaps."""
    from validation.corpus import generate
    from validation.corpus_exact import branch_orbit

    model = generate(181, 55)[180].model()
    gap = model.gap
    exact_far = {}
    for H, tol in ((15, 2e-3), (31, 2e-5)):
        b = mmshbm.backbone(model, harmonics=H, max_amplitude=10 * gap, r="residual")
        assert b.status == "bound:amplitude", b.status
        for a in (2.2, 5.0, 10.0):
            f_exact, share = branch_orbit(model, b, a * gap)
            assert 0.7 < share < 0.8 and f_exact > 4.2, (H, a)  # the far side, above f2/2 = 3.17 Hz
            assert abs(b.frequency_at(a * gap) / f_exact - 1) < tol, (H, a)
            if H == 15:
                exact_far[a] = f_exact
    default = mmshbm.backbone(model, harmonics=15, max_amplitude=10 * gap)
    assert default.status == "bound:amplitude", default.status
    for a, f_exact in exact_far.items():
        assert 0.01 < 1 - default.frequency_at(a * gap) / f_exact < 0.025, a  # the static r's truncation
