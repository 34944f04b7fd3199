"""Forced responses, damped nonlinear modes and phase resonance.

* ``ForcedOscillator``: the one-DOF forced damped oscillator (ζ = 2 %, F = 0.1 N, 0.1–0.3 Hz)
  by each method at *equal accuracy* — the setting that brings the amplitude at 0.185 Hz on
  the upper branch within 1e-3 of the exact event-driven orbit (measured: MMS-HBM H = 10
  6.6e-4; penalty H = 20, k_p = 10⁴ k_c 3.5e-4; shooting 256 steps 3.5e-4); the error is
  tracked.
* ``ForcedBeam``: the default beam (21 elements, 0.5 % modal damping), 2.3 N at the last
  node with mass (the force that holds 5 gaps at phase resonance), 40–60 Hz, H = 5, with and
  without Floquet stability; penalty-HBM at equal H (no converged reference exists on the
  beam; its defaults: k_p = 10³ k_c, the exact projection; with the sampled one it stopped at
  57.1 Hz). Shooting is skipped on the beam (it wanders into rattling families,
  see SKIP_REASONS).
* ``DampedModes``: the EPMC backbone of the beam to 10 gaps (H = 5, 0.5 %; H = 7 with the
  higher modes at 5 %) and the phase-resonance backbone to 5 gaps.
* ``ForcedHarmonics``: the beam with 0.5 % on mode 1 and 5 % above, 5 N at the last node
  with mass, 40–62 Hz, MMS-HBM at H = 5..40 with Floquet stability (the compiled projection;
  goals H = 30 <= 2 s, H = 40 <= 5 s); where the response ends and its points.
* ``EPMCBudget``: the EPMC backbone of that beam at H = 20 with the default step budget:
  time, points and the amplitude reached (goal 6 gaps; the branch closes on a loop of
  folds between 2 and 3.6 gaps after a branch point at 2.9 gaps, so no budget reaches it).
"""

from __future__ import annotations

import functools

import numpy as np

F_OSC = (0.1, 0.0)
FREQ = 0.185
#: equal-accuracy settings (amplitude within 1e-3 of the exact orbit at FREQ)
SETTINGS = {"mmshbm": {"harmonics": 10}, "penalty": {"harmonics": 20, "penalty_stiffness": 1e4 * 0.8},
            "shooting": {"steps_per_period": 256}}
SKIP_SHOOTING_BEAM = ("forced shooting on the default beam follows rattling families near 47 Hz and "
                      "ends at max_steps (3000 points, ~2 min): no comparable response")


@functools.cache
def oscillator():
    import mmshbm

    return mmshbm.OneDofOscillator(1, 1, 4, 1).model().with_damping(modal_ratio=0.02)


@functools.cache
def beam(higher: float | None = None):
    import mmshbm

    m = mmshbm.default_beam().model(21)
    if higher is None:
        return m.with_damping(modal_ratio=0.005)
    return m.with_damping(modal_ratio=[0.005] + [higher] * (len(m.l) - 1))


def beam_force(model):
    F = np.zeros(model.n_dof)
    F[38] = 2.3
    return F


@functools.cache
def exact_amplitude() -> float:
    """Amplitude (m) of the exact upper-branch orbit of the oscillator at FREQ."""
    import mmshbm
    from mmshbm.core.continuation import newton
    from mmshbm.methods.exact.forced import forced_orbit
    from mmshbm.methods.mms.forced import ForcedResponseProblem

    osc = oscillator()
    resp = mmshbm.frequency_response(osc, F_OSC, (0.1, 0.2), harmonics=20, stability=False)
    i = int(np.flatnonzero((resp.frequency > FREQ - 0.004) & (resp.amplitude > 1.5))[0])
    p = ForcedResponseProblem(osc, F_OSC, harmonics=20, stability=False)
    w = 2 * np.pi * FREQ
    u0 = p.pack(resp.solver.unpack(resp.states[i])[0], w)
    t = np.zeros(p.n_unknowns)
    t[-1] = 1.0
    u = newton(p, u0, t, u0.copy(), 1e-12, 40, 1e-14)[0]
    Q = p.coefficients(u)
    k = np.arange(1, 21)
    z0 = np.array([Q[0, 0] + Q[0, 1::2].sum(), w * (k * Q[0, 2::2]).sum()])
    return forced_orbit(osc, F_OSC, FREQ, guess=z0).amplitude(1)


def warm_up() -> None:
    import mmshbm

    osc = oscillator()
    for method, kw in (("mmshbm", {"harmonics": 3}), ("penalty", {"harmonics": 3}),
                       ("shooting", {"steps_per_period": 32})):
        mmshbm.frequency_response(osc, F_OSC, (0.1, 0.12), method=method, **kw)


class ForcedOscillator:
    """Whole frequency responses of the one-DOF oscillator at equal accuracy."""

    params = [("mmshbm", "penalty", "shooting")]
    param_names = ["method"]
    number = 1
    repeat = (1, 5, 30.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self, method):
        warm_up()

    def time_response(self, method):
        import mmshbm

        mmshbm.frequency_response(oscillator(), F_OSC, (0.1, 0.3), method=method, stability=False,
                                  **SETTINGS[method])

    def track_amplitude_error(self, method):
        """Relative amplitude error at FREQ on the upper branch (the response continued up to
        FREQ ends refined onto it) against the exact orbit."""
        import mmshbm

        r = mmshbm.frequency_response(oscillator(), F_OSC, (0.1, FREQ), method=method, stability=False,
                                      **SETTINGS[method])
        return abs(r.amplitude[-1] / exact_amplitude() - 1)

    def track_points(self, method):
        import mmshbm

        return len(mmshbm.frequency_response(oscillator(), F_OSC, (0.1, 0.3), method=method, stability=False,
                                             **SETTINGS[method]))


class ForcedBeam:
    """The default beam's frequency response, 40–60 Hz, H = 5 (2.3 N at node 20)."""

    params = [("mmshbm", "mmshbm-stability", "penalty", "shooting")]
    param_names = ["method"]
    number = 1
    repeat = (1, 3, 60.0)
    warmup_time = 0.0
    timeout = 600

    def setup(self, method):
        if method == "shooting":
            raise NotImplementedError(SKIP_SHOOTING_BEAM)
        warm_up()

    def _run(self, method):
        import mmshbm

        m = beam()
        name = "mmshbm" if method.startswith("mmshbm") else method
        return mmshbm.frequency_response(m, beam_force(m), (40.0, 60.0), harmonics=5, method=name,
                                         stability=method == "mmshbm-stability")

    def time_response(self, method):
        self._run(method)

    def track_points(self, method):
        return len(self._run(method))

    def track_peak_gaps(self, method):
        return float(self._run(method).amplitude.max() / 1e-3)

    def track_end_frequency(self, method):
        """Where the response ends (Hz): 60 when it covers the range."""
        return float(self._run(method).frequency[-1])


class DampedModes:
    """EPMC and phase-resonance backbones of the default beam."""

    number = 1
    repeat = (1, 3, 60.0)
    warmup_time = 0.0
    timeout = 600

    def setup(self):
        warm_up()

    def time_epmc_h5_10_gaps(self):
        import mmshbm

        mmshbm.backbone(beam(), harmonics=5)

    def time_epmc_h7_higher_modes_damped_10_gaps(self):
        import mmshbm

        mmshbm.backbone(beam(0.05), harmonics=7)

    def time_phase_resonance_5_gaps(self):
        from mmshbm.analysis.phase_resonance import phase_resonance_backbone

        m = beam()
        phase_resonance_backbone(m, beam_force(m), harmonics=5, max_amplitude=5e-3)

    def time_conservative_h5_10_gaps(self):
        """The conservative MMS-HBM backbone, for the ratio."""
        import mmshbm

        mmshbm.backbone(mmshbm.default_beam().model(21), harmonics=5)


#: the damped beam of the forced-harmonics figures: 5 N at node 19 (DOF 38), 40–62 Hz
FORCED_H = (5, 10, 20, 30, 40)


def forced_harmonics_response(H: int):
    import mmshbm

    m = beam(0.05)
    F = np.zeros(m.n_dof)
    F[38] = 5.0
    return mmshbm.frequency_response(m, F, (40.0, 62.0), harmonics=H)


class ForcedHarmonics:
    """The damped beam's frequency response (5 N, 40–62 Hz) at growing H."""

    params = [FORCED_H]
    param_names = ["harmonics"]
    number = 1
    repeat = (1, 3, 60.0)
    warmup_time = 0.0
    timeout = 900

    def setup_cache(self):
        """Points and end frequency of every H, from one response each."""
        warm_up()
        out = {}
        for H in FORCED_H:
            r = forced_harmonics_response(H)
            out[H] = (len(r), float(r.frequency[-1]))
        return out

    setup_cache.timeout = 1800

    def setup(self, figures, harmonics):
        warm_up()
        forced_harmonics_response(3)

    def time_response(self, figures, harmonics):
        forced_harmonics_response(harmonics)

    def track_points(self, figures, harmonics):
        return figures[harmonics][0]

    def track_end_frequency(self, figures, harmonics):
        """Where the response ends (Hz): 62 when it covers the range."""
        return figures[harmonics][1]


def epmc_h20():
    import warnings

    import mmshbm

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mmshbm.BranchWarning)
        return mmshbm.backbone(beam(0.05), harmonics=20)


class EPMCBudget:
    """EPMC backbone of the 0.5 %/5 % beam at H = 20 within the default step budget."""

    number = 1
    repeat = (1, 3, 60.0)
    warmup_time = 0.0
    timeout = 900

    def setup_cache(self):
        """(points, largest amplitude in gaps) of one run."""
        warm_up()
        b = epmc_h20()
        return len(b), float(b.amplitude.max() / 1e-3)

    def setup(self, figures):
        warm_up()
        import mmshbm

        mmshbm.backbone(beam(0.05), harmonics=3, max_amplitude=1e-3)

    def time_epmc_h20(self, figures):
        epmc_h20()

    def track_epmc_h20_points(self, figures):
        return figures[0]

    def track_epmc_h20_max_gaps(self, figures):
        """Largest amplitude (gaps) the branch reaches (goal 6)."""
        return figures[1]
