"""Kernels and transforms: the proximal contact map, FFT round trips over N, the
MMS-HBM residual (with and without Jacobian) and the condensation over H and elements.
Kernels are compiled in ``setup``; samples never contain compilation."""

from __future__ import annotations

import numpy as np

from benchmarks.common import HARMONICS, check_feasible, model, warm_up

SAMPLES = (64, 128, 256, 512, 1024, 4096)
RESIDUAL_MODELS = ("oscillator", "beam8", "beam21", "beam100", "beam1000")


class ProximalContact:
    """λ − max(0, λ − r g) and its active set on N samples (Numba kernel)."""

    params = [SAMPLES]
    param_names = ["N"]

    def setup(self, N):
        from mmshbm.contact.unilateral import _proximal_contact

        rng = np.random.default_rng(0)
        self.lam = rng.standard_normal(N)
        self.g = rng.standard_normal(N)
        self.R = np.empty(N)
        self.s = np.empty(N)
        self.kernel = _proximal_contact
        self.kernel(self.lam, self.g, 2.0, self.R, self.s)  # compile / load from cache

    def time_proximal_contact(self, N):
        self.kernel(self.lam, self.g, 2.0, self.R, self.s)


class FFTRoundTrip:
    """Harmonics -> N samples -> harmonics (pyfftw plans, as the AFT of the residual)."""

    params = [SAMPLES, (1, 2)]
    param_names = ["N", "signals"]

    def setup(self, N, signals):
        from mmshbm.harmonic.harmonics import transform

        self.H = max(1, N // 16)
        self.tr = transform(self.H, N, signals)
        rng = np.random.default_rng(0)
        self.a = rng.standard_normal((signals, self.H + 1))
        self.c = rng.standard_normal((signals, 2 * self.H + 1))
        self.tr.time_to_cos(self.tr.cos_to_time(self.a))

    def time_cosine_round_trip(self, N, signals):
        self.tr.time_to_cos(self.tr.cos_to_time(self.a))

    def time_full_round_trip(self, N, signals):
        self.tr.to_harmonics(self.tr.to_time(self.c))


class CosineProductMatrix:
    """P[m, k] of the active set's cosine spectrum (Jacobian of the contact rows)."""

    params = [HARMONICS]
    param_names = ["H"]

    def setup(self, H):
        from mmshbm.contact.projection import _cosine_product_matrix
        from mmshbm.harmonic.harmonics import default_n_samples

        N = default_n_samples(H)
        self.S = np.random.default_rng(0).standard_normal(N)
        self.P = np.empty((H + 1, H + 1))
        self.kernel = _cosine_product_matrix
        self.kernel(self.S, H, self.P)

    def time_cosine_product_matrix(self, H):
        self.kernel(self.S, H, self.P)


class MMSHBMResidual:
    """One evaluation of the MMS-HBM residual and Jacobian, and of the condensation alone,
    at the linear mode scaled to 1.5 gaps (contact active on part of the period)."""

    params = [RESIDUAL_MODELS, HARMONICS]
    param_names = ["model", "H"]

    def setup(self, name, H):
        from mmshbm.methods.registry import make_problem

        check_feasible(name, "mmshbm", H)
        warm_up("mmshbm")
        m = model(name)
        self.problem = make_problem(m, "mmshbm", harmonics=H)
        self.u = self.problem.linear_point(1.5 * m.gap)
        self.omega = self.problem.unpack(self.u)[1]
        self.H = H
        self.problem.evaluate(self.u, jacobian=True)
        # two states whose Ω differ in the last digits, alternated: the problem reuses the
        # condensation at an unchanged Ω, and every Newton iteration changes Ω
        self.states = [self.u, self.u.copy()]
        self.states[1][-1] *= 1 + 1e-12
        self.calls = 0

    def _next_state(self):
        self.calls += 1
        return self.states[self.calls % 2]

    def time_residual(self, name, H):
        self.problem.evaluate(self._next_state(), jacobian=False)

    def time_residual_and_jacobian(self, name, H):
        self.problem.evaluate(self._next_state(), jacobian=True)

    def time_condensation(self, name, H):
        self.problem.cond.dynamic_stiffness(self.omega, self.H, derivative=True)


class AmplitudeGradient:
    """The amplitude and its gradient at a DOF with mass (every pinned Newton iteration of a
    jump): a corpus beam clearance (16 elements, H = 15, 28 pole unknowns on 15
    harmonics), one recovery of the amplitude row per contact DOF, per group of poles with
    distinct harmonics and per Ω difference."""

    def setup(self):
        import warnings

        import mmshbm
        from validation import corpus

        model = corpus.generate(291, 29)[290].model()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            branch = mmshbm.backbone(model, harmonics=15, max_amplitude=1.1 * model.gap)
        self.problem = branch._require_solver()
        self.u = branch.states[len(branch) - 1]
        self.problem.amplitude_and_gradient(self.u)

    def time_amplitude_and_gradient(self):
        self.problem.amplitude_and_gradient(self.u)

    def track_recoveries_per_gradient(self):
        p = self.problem
        return p.n_c + len(p._pole_groups) + 3  # + the peak's row and the two Ω differences
    track_recoveries_per_gradient.unit = "recoveries"
