"""The definition of the first mode's family (docs/resonances.md): the fundamental
harmonic's share of the period-mean kinetic energy, at least ``family_share``. Its
properties, checked on MMS-HBM orbits against the kinetic energy of the time signals."""

import numpy as np
import pytest

import mmshbm
from mmshbm.family.definition import FAMILY_RECORD, family_value, on_family


@pytest.fixture(scope="module")
def beam7():
    """The default beam on 21 elements at H = 7, to 3 gaps (past grazing and the 6:1
    and 5:1 tongues)."""
    model = mmshbm.default_beam().model(21)
    return mmshbm.backbone(model, harmonics=7, max_amplitude=3 * model.gap)


def _signal_share(branch, i: int) -> float:
    """The fundamental's share of the kinetic energy of point ``i`` from the Fourier
    coefficients of the DOFs with mass sampled over a period: T_k ∝ k² Q_kᴴ M Q_k."""
    model = branch.solver.model
    M = model.blocks["M_ll"]
    M = M.toarray() if hasattr(M, "toarray") else np.asarray(M)
    n = 8 * (branch.solver.H + 1)
    _, q = branch.time_signals(i, dofs=model.l, n_samples=n)
    Q = np.fft.rfft(q, axis=1) / n
    k = np.arange(Q.shape[1])
    T = k**2 * np.einsum("ik,ij,jk->k", Q.conj(), M, Q).real
    return float(T[1] / T[1:].sum())


def test_the_linear_mode_is_an_orbit_of_the_family(beam7):
    """The linear first mode has no higher harmonics: share 1 (to round-off), on the family
    whatever the threshold below 1."""
    p = beam7.solver
    u = p.linear_mode_point(0.5 * beam7.solver.model.gap)
    share = p.fundamental_share(u)
    assert abs(share - 1.0) < 1e-12
    assert on_family({FAMILY_RECORD: share}, 0.99)


def test_the_share_is_the_kinetic_energy_of_the_fundamental(beam7):
    """The recorded share (from the condensed stiffness, −(Ω/8) a_kᵀ ∂D_k/∂Ω a_k) equals the
    share computed from the time signals of the DOFs with mass, on orbits before and after
    grazing: both are exact for the truncated series, so they agree to round-off times the
    condensation's conditioning (1e-9)."""
    shares = beam7.records[FAMILY_RECORD]
    picks = [1, len(beam7) // 2, len(beam7) - 1]
    assert shares[picks[-1]] < 1 - 1e-4  # the last orbit has higher harmonics
    for i in picks:
        assert abs(_signal_share(beam7, i) - shares[i]) < 1e-9, i


def test_the_share_is_a_property_of_the_orbit_not_of_its_phase_or_scale(beam7):
    """A half-period time shift (harmonic k times (−1)^k) and a common scale of the motion
    leave the share unchanged (ratios of the same quadratic forms: round-off)."""
    p = beam7.solver
    u = beam7.states[-1]
    a, omega = p.unpack(u)
    share = p.fundamental_share(u)
    sign = (-1.0) ** np.arange(a.shape[0])[:, None]
    shifted = p.pack(sign * a, omega)
    scaled = p.pack(3.7 * a, omega)
    assert abs(p.fundamental_share(shifted) - share) < 1e-12
    assert abs(p.fundamental_share(scaled) - share) < 1e-12


def test_an_orbit_dominated_by_a_higher_harmonic_is_not_of_the_family(beam7):
    """The fundamental's coefficients moved to harmonic 3 (and a tenth left at k = 1): the
    kinetic energy sits at k = 3, the share is below a tenth, and the predicate fails;
    the signals' share agrees (the measure is the kinetic energy, whatever the state)."""
    p = beam7.solver
    a, omega = p.unpack(beam7.states[1])
    moved = np.zeros_like(a)
    moved[1], moved[3] = 0.1 * a[1], a[1]
    share = p.fundamental_share(p.pack(moved, omega))
    assert share < 0.1
    assert on_family({FAMILY_RECORD: share}, 0.5) is False


def test_the_predicate_reads_the_share_with_its_threshold():
    """At the threshold an orbit is on the family, below it not; a record without a
    family measure is undecided (None); records of earlier versions carry mode_share."""
    assert on_family({FAMILY_RECORD: 0.5}, 0.5) is True
    assert on_family({FAMILY_RECORD: np.nextafter(0.5, 0.0)}, 0.5) is False
    assert on_family({"amplitude": 1.0}, 0.5) is None
    assert family_value({"mode_share": 0.7}) == 0.7 and on_family({"mode_share": 0.7}, 0.6) is True


def test_an_orbit_outside_the_first_modes_band_is_not_of_the_family():
    """Condition 2: a dominant fundamental above the band (the second mode's own orbits)
    or below it fails; inside, the share decides."""
    band = (45.0, 75.0)
    assert on_family({FAMILY_RECORD: 0.99, "frequency": 290.0}, 0.5, band) is False
    assert on_family({FAMILY_RECORD: 0.99, "frequency": 44.0}, 0.5, band) is False
    assert on_family({FAMILY_RECORD: 0.99, "frequency": 60.0}, 0.5, band) is True
    assert on_family({FAMILY_RECORD: 0.4, "frequency": 60.0}, 0.5, band) is False


def test_the_band_ends_below_the_second_open_mode_for_one_contact(beam7):
    """Interlacing (one contact: the held structure is a rank-one stiffening of the open
    one): f₁ ≤ f₁^held ≤ f₂. Checked on the beam against its open-contact eigenfrequencies
    computed independently by scipy.linalg.eigh of (K_ll − K_lc K_cc⁻¹ K_cl, M_ll)."""
    import scipy.linalg as la

    from mmshbm.family.definition import frequency_band

    model = beam7.solver.model
    dense = {k: (v.toarray() if hasattr(v, "toarray") else np.asarray(v)) for k, v in model.blocks.items()}
    K = dense["K_ll"] - dense["K_lc"] @ np.linalg.solve(dense["K_cc"], dense["K_lc"].T)
    f = np.sqrt(la.eigh(K, dense["M_ll"], eigvals_only=True)[:2]) / (2 * np.pi)
    lo, hi = frequency_band(beam7.solver, [{"frequency": f[0]}], 0.0)
    assert len(model.contacts) == 1
    assert lo == f[0] and f[0] < hi <= f[1] * (1 + 1e-9)


def test_above_the_second_open_mode_the_first_mode_must_lead_the_fundamental():
    """Condition 3: where the record says another mode leads the fundamental (above f₂)
    the orbit fails, whatever its share; void (NaN or absent) it does not decide."""
    from mmshbm.family.definition import LEAD_RECORD

    assert on_family({FAMILY_RECORD: 0.99, LEAD_RECORD: 0.0}, 0.5) is False
    assert on_family({FAMILY_RECORD: 0.99, LEAD_RECORD: 1.0}, 0.5) is True
    assert on_family({FAMILY_RECORD: 0.99, LEAD_RECORD: float("nan")}, 0.5) is True
    assert on_family({FAMILY_RECORD: 0.4, LEAD_RECORD: 1.0}, 0.5) is False


def test_the_lead_is_void_below_the_second_open_mode_and_read_from_the_modal_shares(beam7):
    """Below f₂ (the beam's backbone stays near f₁ with one contact) every point records
    NaN; at a state whose Ω is set above f₂ the record is 1 exactly when mode 1 holds the
    largest share of harmonic 1 in the modal decomposition (``modal_shares``)."""
    from mmshbm.family.definition import LEAD_RECORD

    leads = np.asarray(beam7.records[LEAD_RECORD], dtype=float)
    assert np.all(np.isnan(leads))
    P = beam7.solver
    f2 = P.tracked_frequencies[1]
    u = np.array(beam7.states[-1], dtype=float)
    omega = 2 * np.pi * 1.1 * f2
    lead = P.mode_leads(u, omega)
    fundamental = P.modal_shares(u)[:, 1]
    assert lead == (1.0 if fundamental[0] >= fundamental.max() else 0.0)
