"""Coulomb friction at massless nodes: MMS-HBM against the Jenkins (penalty-HBM) baseline.

* ``TipDamperPoint``: the default beam (21 elements, 1 % modal damping) with a Coulomb damper
  on its massless tip (μ = 0.5, N = 1 N), 1 N at the node before the tip, one converged
  orbit at 45 Hz, each method at the setting that brings the tip-adjacent amplitude within
  1e-2 of the reference (MMS-HBM at H = 45; the Jenkins baseline approaches it as k_t grows:
  5.8e-2, 1.9e-2, 8.8e-3 at k_t = 10, 100, 1000 ρ with H = 15). Measured: MMS-HBM H = 7
  3.2e-3; Jenkins H = 15, k_t = 10³ ρ, N = 16(2H+1) samples 8.8e-3. The errors are tracked.
* ``JenkinsOscillator``: the one-DOF Jenkins oscillator (m = 1 kg, k1 = 1, k2 = 2 N/m,
  c = 0.05 N·s/m, μN = 0.1 N, 0.1 N at 0.2 Hz), where the spring is physical and the Jenkins
  AFT is exact for the model: accuracy against the exact orbit and cost at equal H, MMS-HBM
  against Jenkins with N = 16(2H+1) and 1024 samples.
* ``NormalLoadStudy``: the 20-load optimal-normal-load study of the tip damper (mid-span
  force and amplitude, 30–250 Hz, H = 7) on 2 worker processes.
* ``TwoMassDamper``: the whole FRF (0.5–2 f₁, H = 15) of a 2-mass chain (1 kg each, springs
  of 10⁴ N/m to ground and between them, 1 % modal damping, 10 N on mass 1) whose mass 2 is
  joined by k_t = 10⁴ N/m to a massless Coulomb slider, μN = 5 N
  (``with_friction(..., tangential_stiffness=)``): MMS-HBM against the Jenkins baseline on
  the same physical spring; ``track_ms_per_point`` the time per FRF point (MMS-HBM, the
  friction rows compiled: 1.5 ms on the 2-core development machine, idle; 4.0–5.1 ms with
  the NumPy rows, docs/friction.md), ``track_cpu_ms_per_point`` its processor time (the
  whole evaluation fused: 1.41–1.58 ms, best of twenty, at load 7–14; 3.4–4.1 ms before;
  the corrector compiled too: 0.37–0.51 ms at load 2.8, 0.62–0.66 ms before).
* ``NLvibFrictionBeam``: NLvib's example-08 beam (2 m, 0.1 × 0.3 m, 185 GPa, 7830 kg/m³, 8
  elements; 0.2 N at the tip, C = βK with 1 % at the first stuck mode), μN = 1.5 N at node 4
  behind k_t = 1e7 or 1e9 N/m, or rigid at node 4 made massless; the whole FRF 0.9 ω_free …
  1.5 ω_stuck at H = 13, with its Newton iterations per point and its processor time.
* ``FrictionEvaluation``: one evaluation and one point's records on that beam (k_t = 1e7),
  the fused kernel against the stepwise path.
* ``ImpactFriction``: impact with friction on 4 DOFs (two masses driving a node's normal and
  tangential DOFs; gap 0.05 m, μ = 0.3, preload 0.05 N), the FRF 0.1–0.3 Hz at H = 7.
* ``FrictionCorrector``: the ex08-like FRF (k_t = 1e7, 1e9) with the corrector compiled and
  with its Python loop.
* ``NLvibSideBySide``: the ex08 beam (k_t = 1e7, 1e9) and the Jenkins oscillator against
  NLvib's figures measured by ``python -m validation nlvib`` (``NLVIB``): the processor-time
  ratio and the rms difference at NLvib's largest point.
"""

from __future__ import annotations

import functools

import numpy as np

TIP_F = 45.0
#: equal-accuracy settings on the tip damper (within 1e-2 of MMS-HBM at H = 45)
TIP_SETTINGS = {"mmshbm": {"harmonics": 7}, "penalty": {"harmonics": 15, "factor": 1e3}}
OSC_F = 0.2


@functools.cache
def tip_model():
    import mmshbm

    return mmshbm.tip_damper_model(normal_load=1.0)


@functools.cache
def tip_reference() -> float:
    from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

    m = tip_model()
    p = FrictionForcedProblem(m, _tip_force(), 45)
    return p.monitor(p.start_point(TIP_F))["amplitude"]


def _tip_force():
    import mmshbm

    return mmshbm.tip_damper_force(tip_model())


def tip_problem(method: str):
    from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
    from mmshbm.methods.penalty.jenkins import JenkinsForcedProblem

    kw = TIP_SETTINGS[method]
    if method == "mmshbm":
        return FrictionForcedProblem(tip_model(), _tip_force(), kw["harmonics"])
    H = kw["harmonics"]
    rho = JenkinsForcedProblem(tip_model(), _tip_force(), H)._rho[0]
    return JenkinsForcedProblem(tip_model(), _tip_force(), H, tangential_stiffness=kw["factor"] * rho,
                                n_samples=16 * (2 * H + 1))


class TipDamperPoint:
    """One converged orbit of the beam's tip damper at 45 Hz at equal accuracy."""

    params = [("mmshbm", "penalty")]
    param_names = ["method"]
    number = 1
    repeat = (3, 10, 30.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self, method):
        self.problem = tip_problem(method)
        self.problem.start_point(TIP_F)  # kernels compiled or loaded outside the samples

    def time_orbit(self, method):
        self.problem.start_point(TIP_F)

    def track_amplitude_error(self, method):
        u = self.problem.start_point(TIP_F)
        return abs(self.problem.monitor(u)["amplitude"] / tip_reference() - 1)


@functools.cache
def jenkins_oscillator():
    import mmshbm

    M = np.diag([1.0, 0.0])
    K = np.array([[3.0, -2.0], [-2.0, 2.0]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([0.05, 0.0]), amplitude_dof=0)
    return base.with_friction(1, 0.5, normal_load=0.2)


@functools.cache
def jenkins_exact() -> float:
    from mmshbm.methods.exact.friction import friction_orbit

    return friction_orbit(jenkins_oscillator(), [0.1, 0.0], OSC_F).amplitude(0)


class JenkinsOscillator:
    """The Jenkins oscillator at 0.2 Hz: MMS-HBM and the exact Jenkins AFT side by side."""

    params = [("mmshbm", "jenkins-16(2H+1)", "jenkins-1024"), (7, 15, 31)]
    param_names = ["method", "H"]
    number = 1
    repeat = (3, 10, 30.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self, method, H):
        from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
        from mmshbm.methods.penalty.jenkins import JenkinsForcedProblem

        model = jenkins_oscillator()
        if method == "mmshbm":
            self.problem = FrictionForcedProblem(model, [0.1, 0.0], H)
        else:
            N = 16 * (2 * H + 1) if method == "jenkins-16(2H+1)" else 1024
            self.problem = JenkinsForcedProblem(model, [0.1, 0.0], H, tangential_stiffness="physical",
                                                n_samples=N)
        self.problem.start_point(OSC_F)

    def time_orbit(self, method, H):
        self.problem.start_point(OSC_F)

    def track_amplitude_error(self, method, H):
        u = self.problem.start_point(OSC_F)
        return abs(self.problem.monitor(u)["amplitude"] / jenkins_exact() - 1)


def _study_model(normal_load):
    import mmshbm

    return mmshbm.tip_damper_model(normal_load=normal_load, at=0.5)


class NormalLoadStudy:
    """The 20-load optimal-normal-load study of the tip damper, 2 worker processes."""

    number = 1
    repeat = (1, 3, 60.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self):
        import mmshbm

        self.force = mmshbm.tip_damper_force(_study_model(0.0))
        self.loads = np.concatenate([[0.0], np.geomspace(0.05, 50, 19)])
        mmshbm.normal_load_study(_study_model, self.loads[:2], self.force, (40, 50), harmonics=3)

    def time_study(self):
        import mmshbm

        mmshbm.normal_load_study(_study_model, self.loads, self.force, (30, 250), harmonics=7, workers=2)


@functools.cache
def two_mass_damper():
    import mmshbm

    M = np.diag([1.0, 1.0])
    K = np.array([[2e4, -1e4], [-1e4, 1e4]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], amplitude_dof=1).with_damping(modal_ratio=0.01)
    return base.with_friction(1, 0.5, normal_load=10.0, tangential_stiffness=1e4)


DAMPER_FORCE = [10.0, 0.0, 0.0]


class TwoMassDamper:
    """The 2-mass friction damper's whole FRF at H = 15, MMS-HBM and the Jenkins baseline."""

    params = [("mmshbm", "penalty")]
    param_names = ["method"]
    number = 1
    repeat = (3, 10, 60.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self, method):
        model = two_mass_damper()
        f1 = float(model.linear_frequencies(1)[0])
        self.band = (0.5 * f1, 2.0 * f1)
        self.run(method)  # kernels compiled or loaded outside the samples

    def run(self, method):
        import mmshbm

        return mmshbm.frequency_response(two_mass_damper(), DAMPER_FORCE, self.band, harmonics=15,
                                         method=method)

    def time_frf(self, method):
        self.run(method)

    def track_ms_per_point(self, method):
        import time

        t0 = time.perf_counter()
        r = self.run(method)
        return 1e3 * (time.perf_counter() - t0) / len(r.frequency)

    track_ms_per_point.unit = "ms"

    def track_cpu_ms_per_point(self, method):
        """Processor time per point (ms), the best of five whole FRFs (the steady measure on
        a shared machine)."""
        return min(_cpu_ms(lambda: self.run(method), per_point=True) for _ in range(5))

    track_cpu_ms_per_point.unit = "ms"


def _cpu_ms(run, per_point: bool = False) -> float:
    """Processor time (ms) of ``run()``, per point of the response it returns with
    ``per_point``."""
    import time

    c0 = time.process_time()
    r = run()
    ms = 1e3 * (time.process_time() - c0)
    return ms / len(r.frequency) if per_point else ms


@functools.cache
def nlvib_friction_beam(kind: str):
    """NLvib's example-08 beam with Coulomb at node 4: ``kind`` "1e7" / "1e9" (a slider behind
    that k_t, N/m) or "rigid" (node 4's translational mass and damping removed, the friction
    on it). Returns (model, force, band in Hz)."""
    import scipy.linalg as la

    import mmshbm
    from mmshbm.fe.euler_bernoulli import cantilever

    M, K, dofs = cantilever(2.0, 0.3, 0.1, 185e9, 7830.0, 8)
    Md, Kd = M.toarray(), K.toarray()
    node4, tip = int(dofs[3, 0]), int(dofs[-1, 0])
    keep = [i for i in range(len(Md)) if i != node4]
    w_free = np.sqrt(la.eigh(Kd, Md, eigvals_only=True)[0])
    w_stuck = np.sqrt(la.eigh(Kd[np.ix_(keep, keep)], Md[np.ix_(keep, keep)], eigvals_only=True)[0])
    C = (2e-2 / w_stuck) * Kd
    if kind == "rigid":
        for A in (Md, C):
            A[node4, :] = 0.0
            A[:, node4] = 0.0
        model = mmshbm.Model.from_matrices(Md, Kd, [], [], [], damping=C, amplitude_dof=tip)
        model = model.with_friction(node4, 1.0, normal_load=1.5)
    else:
        model = mmshbm.Model.from_matrices(M, K, [], [], [], damping=C, amplitude_dof=tip)
        model = model.with_friction(node4, 1.0, normal_load=1.5, tangential_stiffness=float(kind))
    force = np.zeros(model.n_dof)
    force[tip] = 0.2
    return model, force, (0.9 * w_free / (2 * np.pi), 1.5 * w_stuck / (2 * np.pi))


class NLvibFrictionBeam:
    """The whole ex08-like FRF at H = 13 by MMS-HBM."""

    params = [("1e7", "1e9", "rigid")]
    param_names = ["tangential_stiffness"]
    number = 1
    repeat = (3, 10, 60.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self, kind):
        self.run(kind)

    def run(self, kind):
        import mmshbm

        model, force, band = nlvib_friction_beam(kind)
        return mmshbm.frequency_response(model, force, band, harmonics=13)

    def time_frf(self, kind):
        self.run(kind)

    def track_newton_per_point(self, kind):
        return float(self.run(kind).newton_iterations.mean())

    def track_cpu_ms(self, kind):
        """Processor time of the whole FRF (ms), best of three."""
        return min(_cpu_ms(lambda: self.run(kind)) for _ in range(3))

    track_cpu_ms.unit = "ms"


class FrictionEvaluation:
    """One residual-and-Jacobian evaluation of the ex08-like beam (k_t = 1e7 N/m, H = 13) at
    its stick–slip resonance: the fused kernel (:mod:`mmshbm.methods.mms.friction_fused`)
    against the stepwise path (condensation, fused residual, friction rows, tracked harmonic
    and scaling called from Python), and one point's records."""

    params = [("fused", "stepwise")]
    param_names = ["path"]
    number = 200
    repeat = (3, 10, 30.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self, path):
        from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

        model, force, _ = nlvib_friction_beam("1e7")
        self.problem = p = FrictionForcedProblem(model, force, 13)
        self.u = p.start_point(1.1 * p.linear_frequency)
        self.x, self.omega = p.unpack(self.u)
        p._evaluate(self.u, True)
        if path == "stepwise":
            p._fused = False
        p.monitor(self.u)

    def time_evaluate(self, path):
        self.problem._evaluate(self.u, True)

    def time_residual(self, path):
        self.problem._evaluate(self.u, False)

    def time_record(self, path):
        self.problem.monitor(self.u)


class ImpactFriction:
    """Impact with friction on 4 DOFs, the FRF 0.1–0.3 Hz at H = 7."""

    number = 1
    repeat = (3, 10, 60.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self):
        self.run()

    def run(self):
        import mmshbm

        M = np.diag([1.0, 1.0, 0.0, 0.0])
        K = np.array([[5.5, -0.5, -4, 0], [-0.5, 3.5, 0, -2], [-4, 0, 4, 0], [0, -2, 0, 2]], float)
        base = mmshbm.Model.from_matrices(M, K, [2], [0.05], [+1], damping=np.diag([0.05, 0.05, 0.0, 0.0]),
                                          amplitude_dof=0)
        model = base.with_friction(3, 0.3, normal_contact=0, preload=0.05)
        return mmshbm.frequency_response(model, [0.1, 0.1, 0.0, 0.0], (0.1, 0.3), harmonics=7)

    def time_frf(self):
        self.run()


#: NLvib 1.3 (github.com/maltekrack/NLvib) under GNU Octave 7.3 with OpenBLAS on one thread,
#: fsolve TolFun = TolX = 1e-10, measured by ``python -m validation nlvib`` (the Octave drivers
#: validation/nlvib/*.m, NLvib's own HB_residual and solve_and_continue) on the 2-core
#: development machine ("vm", x86_64), in one sitting with the MMS-HBM runs of that command
#: (docs/friction.md): the warm whole FRF by its example's sequential continuation, H = 13,
#: N samples per period. ``cpu_s``: NLvib's processor time (the steady measure on the shared
#: machine: its own time, not the time others hold the cores), ``wall_s`` its wall time under
#: the load average ``load``; ``points`` its FRF's points; ``peak``: its largest point (Ω in
#: rad/s, rms of the tip or the oscillator's mass in m). The ex08 beam at k_t = 1e9 N/m stops
#: at 177.46 rad/s (fsolve fails there, the step at its minimum).
NLVIB = {
    "1e7": {"N": 128, "cpu_s": 8.66, "wall_s": 69.9, "load": "12.7-16.8", "points": 54,
            "peak": (133.4598, 9.461876e-07), "date": "2026-12-02"},
    "1e9": {"N": 128, "cpu_s": 40.97, "wall_s": 305.4, "load": "16.8-17.8", "points": 44,
            "peak": (183.4598, 8.860128e-08), "date": "2026-12-02"},
    "oscillator-N128": {"N": 128, "cpu_s": 3.55, "wall_s": 11.2, "load": "17.8-16.4", "points": 101,
                        "peak": (1.2200, 1.160890e-01), "date": "2026-12-02"},
    "oscillator-N1024": {"N": 1024, "cpu_s": 18.13, "wall_s": 43.8, "load": "16.4-14.6", "points": 101,
                         "peak": (1.2200, 1.160355e-01), "date": "2026-12-02"},
}


def nlvib_case(kind: str):
    """(model, force, band (Hz), compared DOF) of the MMS-HBM side of :data:`NLVIB`'s ``kind``
    ("1e7", "1e9": the ex08 beam's tip; "oscillator": the Jenkins oscillator's mass on
    0.5–2.5 rad/s, NLvib's band)."""
    if kind == "oscillator":
        return jenkins_oscillator(), np.array([0.1, 0.0]), (0.5 / (2 * np.pi), 2.5 / (2 * np.pi)), 0
    model, force, band = nlvib_friction_beam(kind)
    return model, force, band, model.amplitude_dof


class NLvibSideBySide:
    """MMS-HBM against NLvib's recorded figures (:data:`NLVIB`): the whole FRF at H = 13.
    ``track_cpu_ratio``: NLvib's processor time over MMS-HBM's (one run here; NLvib at
    N = 128, its example's sampling); ``track_rms_difference_at_nlvib_peak``: MMS-HBM's rms at
    the frequency of NLvib's largest point (a fixed-frequency solve) against NLvib's rms
    there, relative (the oscillator against NLvib at N = 1024, whose AFT sampling error is
    smaller)."""

    params = [("1e7", "1e9", "oscillator")]
    param_names = ["case"]
    number = 1
    repeat = (3, 10, 60.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self, kind):
        self.response = self.run(kind)

    def run(self, kind):
        import mmshbm

        model, force, band, _ = nlvib_case(kind)
        return mmshbm.frequency_response(model, force, band, harmonics=13)

    def time_frf(self, kind):
        self.run(kind)

    def track_cpu_ratio(self, kind):
        import time

        ref = NLVIB["oscillator-N128" if kind == "oscillator" else kind]["cpu_s"]
        c0 = time.process_time()
        self.run(kind)
        return ref / (time.process_time() - c0)

    track_cpu_ratio.unit = "ratio"

    def track_rms_difference_at_nlvib_peak(self, kind):
        omega, rms_ref = NLVIB["oscillator-N1024" if kind == "oscillator" else kind]["peak"]
        r = self.response
        solver, dof = r.solver, nlvib_case(kind)[3]
        guess = r.states[int(np.argmin(np.abs(r.angular_frequency - omega)))]
        u, ok = solver.solve_at(omega / (2 * np.pi), guess)
        if not ok:
            return float("nan")
        c = solver.coefficients(u)[dof]
        return abs(float(np.sqrt(c[0] ** 2 + 0.5 * np.sum(c[1:] ** 2))) / rms_ref - 1)

    track_rms_difference_at_nlvib_peak.unit = "relative difference"


class FrictionCorrector:
    """The ex08-like FRF at H = 13 with the corrector compiled (one kernel call per point,
    :meth:`~mmshbm.methods.mms.friction_fused.FusedFrictionEvaluation.correct`) and with the
    Python loop it compiles (``compiled_corrector = False``), processor time, best of three."""

    params = [("1e7", "1e9"), ("compiled", "python")]
    param_names = ["tangential_stiffness", "corrector"]
    number = 1
    repeat = (3, 10, 60.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self, kind, corrector):
        from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

        self._saved = FrictionForcedProblem.compiled_corrector
        FrictionForcedProblem.compiled_corrector = corrector == "compiled"
        self.run(kind)

    def teardown(self, kind, corrector):
        from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

        FrictionForcedProblem.compiled_corrector = self._saved

    def run(self, kind):
        import mmshbm

        model, force, band = nlvib_friction_beam(kind)
        return mmshbm.frequency_response(model, force, band, harmonics=13)

    def track_cpu_ms(self, kind, corrector):
        return min(_cpu_ms(lambda: self.run(kind)) for _ in range(3))

    track_cpu_ms.unit = "ms"
