"""NLvib side by side: its example 08 with a Jenkins element and the Jenkins oscillator,
run by NLvib under Octave and by MMS-HBM in the same sitting.

The Octave drivers are ``validation/nlvib/ex08_jenkins.m`` and
``validation/nlvib/jenkins_oscillator.m``; NLvib itself is not part of this repository
(``--nlvib DIR``: a checkout of github.com/maltekrack/NLvib). Its ``SRC`` is copied to a
temporary folder and patched there for Octave (``optimset(optimset(@fsolve), ...)`` becomes
``optimset(...)``). Its fsolve runs at TolFun = TolX = 1e-10: with Octave's defaults NLvib
accepts unconverged points.

Per case: NLvib's warm wall and processor times (the best runs after the first in one Octave
session), its points and fsolve iterations; MMS-HBM's warm wall and processor times (best of
``repeats`` after a first run), its points and Newton iterations per point; the ratios; the
rms of the tip (the oscillator's mass) at NLvib's converged frequencies by MMS-HBM's fixed-frequency solves
against NLvib's rms there (largest relative difference over the points, and at NLvib's
largest point), and the peak of each FRF as computed (NLvib's from its sampled points).

Absolute times depend on the machine and its load (``os.getloadavg()`` is recorded, before
and after): quote the ratios. On a shared machine the processor times are the steadier
measure (a process's own time, not the time others hold the cores); both sides run with one
BLAS thread (OPENBLAS_NUM_THREADS = OMP_NUM_THREADS = 1 for Octave; set them for this
process too) so that the processor time is the wall time of an idle machine.
"""

from __future__ import annotations

import os
import platform
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["CASES", "NLvibComparison", "patched_nlvib", "run_case", "octave_available"]

HERE = Path(__file__).parent / "nlvib"
H = 13
#: (driver call with {src} and {out}, MMS-HBM side) per case
CASES = {
    "ex08-kt1e7": ("ex08_jenkins('{src}', 1e7, 13, 128, 5, '{out}', {repeats})", "1e7"),
    "ex08-kt1e9": ("ex08_jenkins('{src}', 1e9, 13, 128, 5, '{out}', {repeats})", "1e9"),
    "oscillator-N128": ("jenkins_oscillator('{src}', 13, 128, 2.5, 0.5, 0.02, '{out}', {repeats})",
                        "oscillator"),
    "oscillator-N1024": ("jenkins_oscillator('{src}', 13, 1024, 2.5, 0.5, 0.02, '{out}', {repeats})",
                         "oscillator"),
}
_OPTIMSET = "optimset(optimset(@fsolve),"


def octave_available() -> str | None:
    """Path of the ``octave`` executable, or None."""
    return shutil.which("octave")


def patched_nlvib(nlvib: Path, into: Path) -> Path:
    """NLvib's ``SRC`` copied into ``into`` with the Octave patch; returns the copy's path.
    Raises FileNotFoundError when ``nlvib`` holds no SRC/solve_and_continue.m."""
    src = Path(nlvib) / "SRC"
    if not (src / "solve_and_continue.m").is_file():
        raise FileNotFoundError(f"--nlvib {nlvib}: no SRC/solve_and_continue.m there (an NLvib checkout?)")
    dest = Path(into) / "SRC"
    shutil.copytree(src, dest)
    path = dest / "solve_and_continue.m"
    path.write_text(path.read_text().replace(_OPTIMSET, "optimset("))
    return dest


@dataclass
class NLvibComparison:
    case: str
    nlvib_seconds: float
    nlvib_cpu_seconds: float
    nlvib_cold_seconds: float
    nlvib_points: int
    nlvib_iterations: int
    nlvib_peak: tuple  # (Ω rad/s, rms) of NLvib's largest point
    mmshbm_seconds: float
    mmshbm_cpu_seconds: float
    mmshbm_points: int
    mmshbm_newton_per_point: float
    mmshbm_peak: tuple  # (Ω rad/s, rms) of MMS-HBM's largest point
    rms_difference_max: float  # over NLvib's points, MMS-HBM at the same Ω
    rms_difference_at_peak: float  # at NLvib's largest point
    load: tuple = field(default_factory=tuple)  # 1-min load average before, after

    @property
    def ratio(self) -> float:
        """NLvib's warm wall time over MMS-HBM's."""
        return self.nlvib_seconds / self.mmshbm_seconds

    @property
    def cpu_ratio(self) -> float:
        """NLvib's warm processor time over MMS-HBM's."""
        return self.nlvib_cpu_seconds / self.mmshbm_cpu_seconds


def _oscillator():
    from benchmarks.bench_friction import jenkins_oscillator

    return jenkins_oscillator(), np.array([0.1, 0.0]), (0.5 / (2 * np.pi), 2.5 / (2 * np.pi)), 0


def _mmshbm_case(kind: str):
    """(model, force, band (Hz), the DOF compared) of the MMS-HBM side."""
    if kind == "oscillator":
        return _oscillator()
    from benchmarks.bench_friction import nlvib_friction_beam

    model, force, band = nlvib_friction_beam(kind)
    return model, force, band, model.amplitude_dof


def _rms(c: np.ndarray) -> float:
    """rms of NLvib-ordered coefficients (2H+1,)."""
    return float(np.sqrt(c[0] ** 2 + 0.5 * np.sum(c[1:] ** 2)))


def _run_mmshbm(kind: str, repeats: int):
    import mmshbm

    model, force, band, dof = _mmshbm_case(kind)
    run = lambda: mmshbm.frequency_response(model, force, band, harmonics=H)  # noqa: E731
    r = run()  # kernels compiled or loaded outside the timing
    best = cpu = np.inf
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        r = run()
        best, cpu = min(best, time.perf_counter() - t0), min(cpu, time.process_time() - c0)
    return r, best, cpu, dof


def _rms_at(response, dof: int, omegas: np.ndarray) -> np.ndarray:
    """MMS-HBM's rms of ``dof`` at the angular frequencies ``omegas`` (rad/s): Newton at each
    fixed frequency from the branch's nearest point."""
    solver = response.solver
    w = response.angular_frequency
    out = np.empty(len(omegas))
    for i, om in enumerate(omegas):
        guess = response.states[int(np.argmin(np.abs(w - om)))]
        u, ok = solver.solve_at(om / (2 * np.pi), guess)
        out[i] = _rms(solver.coefficients(u)[dof]) if ok else np.nan
    return out


def run_case(case: str, src: Path, out: Path, repeats: int = 2) -> NLvibComparison:
    """One case of :data:`CASES` (NLvib under Octave, then MMS-HBM)."""
    call, kind = CASES[case]
    prefix = out / case
    load0 = os.getloadavg()[0]
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    # run in the output folder: Octave may leave its octave-workspace file where it runs
    subprocess.run(["octave", "--no-gui", "--quiet", "--path", str(HERE), "--eval",
                    call.format(src=src, out=prefix, repeats=max(2, repeats))],
                   cwd=out, check=True, capture_output=True, timeout=3600, env=env)
    summary = np.atleast_2d(np.loadtxt(f"{prefix}_summary.csv", delimiter=","))
    points = np.atleast_2d(np.loadtxt(f"{prefix}_points.csv", delimiter=","))
    om_ref, rms_ref = points[:, 0], points[:, 1]
    r, seconds, cpu, dof = _run_mmshbm(kind, repeats)
    load1 = os.getloadavg()[0]
    rms = _rms_at(r, dof, om_ref)
    diff = np.abs(rms / rms_ref - 1)
    i_ref = int(np.argmax(rms_ref))
    rms_branch = r.rms(dof)
    i = int(np.argmax(rms_branch))
    return NLvibComparison(
        case=case, nlvib_seconds=float(summary[1:, 0].min()), nlvib_cpu_seconds=float(summary[1:, 1].min()),
        nlvib_cold_seconds=float(summary[0, 0]), nlvib_points=int(summary[0, 2]),
        nlvib_iterations=int(summary[0, 3]),
        nlvib_peak=(float(om_ref[i_ref]), float(rms_ref[i_ref])), mmshbm_seconds=seconds,
        mmshbm_cpu_seconds=cpu, mmshbm_points=len(r.frequency),
        mmshbm_newton_per_point=float(r.newton_iterations.mean()),
        mmshbm_peak=(float(r.angular_frequency[i]), float(rms_branch[i])),
        rms_difference_max=float(np.nanmax(diff)), rms_difference_at_peak=float(diff[i_ref]),
        load=(load0, load1))


def machine() -> str:
    return f"{platform.node()} {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs"


def run(nlvib: Path, cases=None, repeats: int = 2, out: Path | None = None) -> list[NLvibComparison]:
    """Every case (default all of :data:`CASES`); the Octave outputs go to ``out`` (default
    a temporary folder). Raises RuntimeError without Octave."""
    if octave_available() is None:
        raise RuntimeError("octave is not on PATH: install it (apt-get install octave) to run NLvib")
    with tempfile.TemporaryDirectory() as tmp:
        src = patched_nlvib(nlvib, Path(tmp))
        dest = Path(out) if out is not None else Path(tmp)
        dest.mkdir(parents=True, exist_ok=True)
        return [run_case(c, src, dest, repeats) for c in (cases or list(CASES))]


def report(results: list[NLvibComparison]) -> str:
    """One line per case: times (wall / processor, s), points, ratios, peaks, differences."""
    lines = ["case: NLvib wall/cpu s (points) | MMS-HBM wall/cpu s (points, Newton/point) | ratio wall/cpu | "
             "NLvib's largest point (rad/s, rms) | MMS-HBM's | rms difference at NLvib's points: max, at "
             "its largest | load before-after"]
    for c in results:
        lines.append(
            f"{c.case}: {c.nlvib_seconds:.2f}/{c.nlvib_cpu_seconds:.2f} ({c.nlvib_points}) | "
            f"{c.mmshbm_seconds:.3f}/{c.mmshbm_cpu_seconds:.3f} ({c.mmshbm_points}, "
            f"{c.mmshbm_newton_per_point:.2f}) | {c.ratio:.0f}/{c.cpu_ratio:.0f} | "
            f"{c.nlvib_peak[0]:.4f}, {c.nlvib_peak[1]:.6e} | "
            f"{c.mmshbm_peak[0]:.4f}, {c.mmshbm_peak[1]:.6e} | "
            f"{c.rms_difference_max:.2e}, {c.rms_difference_at_peak:.2e} | {c.load[0]:.1f}-{c.load[1]:.1f}")
    lines.append(f"machine: {machine()}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    return "\n".join(lines)
