"""Jumps that land by continuing the orbit in the harmonics (mmshbm.core.family's last
resort, MMS-HBM's ``harmonic_landing``)."""

import numpy as np
import scipy.linalg as la

import mmshbm
from mmshbm.analysis import corpus


def _held_frequency(model) -> float:
    """First eigenfrequency (Hz) with every contact DOF held (K_ll, M_ll): the frequency a
    clearance's backbone tends to far above the gaps, where the mass spends the period in
    contact with both stops' springs as with one linear spring."""
    b = model.blocks
    K, M = (np.asarray(x.toarray() if hasattr(x, "toarray") else x) for x in (b["K_ll"], b["M_ll"]))
    return float(np.sqrt(la.eigh(K, M, eigvals_only=True)[0]) / (2 * np.pi))


def test_a_clearance_lands_from_the_fundamental_alone_where_the_h3_family_ends():
    """A heavy mass (84.8 kg) held by a stiff clearance in a 3-mass chain, H = 15: the
    backbone climbs from the open frequency (0.050 Hz) towards the one with the contact
    held (0.2512 Hz) and meets the second open mode (0.266 Hz) on the way; the branch
    climbs the tongue onto that mode (the fundamental's share 0), and so does the
    auxiliary H = 3 branch, which ends below 1.8 gaps, so no predictor reaches the family
    above. The family with the fundamental alone (H = 1) meets no such tongue; its orbit
    raised to H = 15 two harmonics at a time lands, and the backbone reaches 10 gaps just
    below the held frequency (closed form: the eigenvalue with the contact held;
    measured 1.5e-5 below it)."""
    case = corpus.generate(169, seed=0, contacts=("clearance",))[168]
    assert (case.kind, case.harmonics, len(case.params["masses"])) == ("chain", 15, 3)
    model = case.model()
    b = mmshbm.backbone(model, harmonics=15, max_amplitude=10 * model.gap)
    assert b.status == "bound:amplitude" and b.records["on_family"][-1] == 1.0
    assert b.records["fundamental_share"][-1] > 0.99
    f_held = _held_frequency(model)
    assert 0 < 1 - b.frequency[-1] / f_held < 1e-4


def _fundamental_share(model, orbit) -> float:
    """The fundamental's share of the period-mean kinetic energy of an exact orbit, from
    its velocities sampled at 2048 instants (harmonics 1..1024)."""
    M = model.blocks["M_ll"]
    M = np.asarray(M.toarray() if hasattr(M, "toarray") else M)
    n = 2048
    V = np.array([orbit.trajectory.v(t)[model.l] for t in np.arange(n) * orbit.period / n])
    C = np.fft.rfft(V, axis=0) / n
    E = np.einsum("ki,ij,kj->k", C.conj(), M, C).real
    return float(E[1] / E[1:].sum())


def test_a_landing_above_the_zero_gap_frequency_is_refused():
    """A 7-mass chain (one-sided, H = 9; f1 = 0.0934 Hz, f2 = 0.1931 Hz) meets 2Ω = f2:
    its exact orbit (continued from the linear mode in steps of 0.05 gaps) has lost the
    fundamental's majority at the branch's frontier, 1.62 gaps (measured share 0.45, the
    second harmonic 1.2 times the fundamental's energy), and loses more beyond it. The
    harmonic ladder finds an orbit with the majority at 3.70 gaps, at 0.1299 Hz: 5.7 %
    above the zero-gap frequency 0.1228 Hz, which the first mode's backbone approaches
    from below, so another mode's branch. Refused, the run ends at the frontier ("family ended"), where
    the branch is the exact orbit (measured 3.7e-4, the truncation at H = 9)."""
    case = corpus.generate(97, seed=11)[96]
    assert (case.kind, case.contact, case.harmonics) == ("chain", "one-sided", 9)
    model = case.model()
    b = mmshbm.backbone(model, harmonics=9, max_amplitude=10 * model.gap)
    on = b.records["on_family"] == 1.0
    assert b.frequency[on].max() <= model.zero_gap_frequency()
    assert b.status.kind == "family ended"
    front = b.family_front()
    i = front[int(np.argmax(b.amplitude[front]))]
    top = b.amplitude[i] / model.gap
    ex = mmshbm.exact.backbone(model, model.gap * np.append(np.arange(0.9, top, 0.05), top))
    assert ex.converged[-1] and ex.n_contacts[-1] == 1
    assert abs(b.frequency[i] / ex.frequency[-1] - 1) < 1e-3
    assert _fundamental_share(model, ex.orbits[-1]) < 0.5
