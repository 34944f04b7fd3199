"""Accuracy against cost: MMS-HBM, penalty-HBM and shooting at equal accuracy.

``mmshbm bench`` calls :func:`compare_methods`, prints :func:`format_table` and writes
:func:`write_results`. Each method is *tuned* to an accuracy target in the relative error
of the backbone frequency at one amplitude (default :data:`DEFAULT_AMPLITUDE_GAPS`: 2 gaps
on the oscillator, 1.5 on the beam) against a reference, then its
whole backbone (from half a gap up to that amplitude, compiled kernels, the fastest of
``repeats`` runs) is timed.

Tuning. Each method walks a ladder of its resolution parameter (MMS-HBM: the harmonics
H; penalty-HBM: H for each penalty stiffness k_p = factor · k_c; shooting: time steps per
period). Harmonic-balance errors of a nonsmooth problem are not monotone in H (a lucky
H can hit the target by cancellation and the next one miss it), so a setting counts as
reaching the target only if it **and the next rung of the ladder** both do ("robustly
converged to the target"); the cheapest such setting is chosen. A method that never
gets there is reported with its most accurate setting and ``target_met = False``.

References (column ``reference``):

* one-DOF oscillator: the closed form :meth:`~mmshbm.fe.oscillator.OneDofOscillator.frequency`;
* beam: :func:`mmshbm.methods.exact.periodic_orbit` started from the MMS-HBM (H = 5) orbit, if it
  converges; otherwise MMS-HBM at H = 40 if H = 25 agrees with it to a tenth of the target
  (both following the first mode's family, the default continuation); otherwise (*equal
  H*, docs/design.md §5: "compare methods on the beam at equal H")
  the H = 5 MMS-HBM solution with N = 1024 samples, i.e. the nonlinear mode of the
  5-harmonic problem converged in N. Then both harmonic-balance methods use H = 5
  (MMS-HBM's only free resolution is N; penalty-HBM is tuned in k_p) and shooting, which
  does not truncate harmonics, is measured against the same number: its error there is
  the difference of the models, not its time-step error, and is reported as such.
  On the default beam above grazing the last case is the one that applies: the exact
  orbits rattle (many contacts per period) and the solver does not converge, and the
  frequency is not converged in H to 1e-4 at any amplitude (at 1.5 gaps, H = 5 / 7 / 9 /
  11 / 15 / 25 give 54.75 / 55.06 / 55.01 / 54.95 / 54.87 / 55.01 Hz: internal
  resonances with higher modes keep entering as H grows). Equal accuracy against a true
  reference is measured on the one-DOF oscillator.

Timings are wall-clock on whatever machine runs this; on a shared machine they are noisy
(take the ratios as order-of-magnitude figures). Peak memory is the ``tracemalloc`` peak
of one whole backbone (Python and NumPy allocations; not the process RSS).
"""

from __future__ import annotations

import csv
import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._method_info import benchmarked_methods, is_harmonic_balance, method_info
from .backbone_timing import backbone_with as _backbone
from .backbone_timing import measure as _measure
from .backbone_timing import reached_frequency as _reached_frequency
from .element_scaling import element_scaling, format_scaling

__all__ = ["compare_methods", "format_table", "write_results", "element_scaling", "format_scaling",
           "METHOD_NAMES", "load_model", "DEFAULT_AMPLITUDE_GAPS", "default_amplitude"]

log = logging.getLogger(__name__)

#: display names of the compared methods (:func:`~mmshbm._method_info.benchmarked_methods`)
METHOD_NAMES = {name: method_info(name).display_name for name in benchmarked_methods()}

# ladders of the resolution parameters: (full, quick)
_H_LADDER = ((1, 3, 5, 7, 9, 11, 13, 15, 20, 25, 30, 40), (3, 5, 9, 15, 25))
_PENALTY_H = ((5, 9, 15, 25, 40), (9, 15, 25))
_PENALTY_FACTORS = ((1e2, 1e3, 1e4, 1e5, 1e6), (1e3, 1e4, 1e5))
_STEPS = ((32, 64, 128, 256, 512, 1024, 2048, 4096), (64, 128, 256, 512, 1024))
_BEAM_STEPS = ((128, 256, 512, 1024, 2048), (128, 256))
#: equal-H fallback on the beam: the paper's H, and the N of the reference solution
_EQUAL_H = 5
_REFERENCE_N = 1024
#: high-H reference check on the beam
_HIGH_H = (25, 40)

_COLUMNS = ["model", "method", "setting", "harmonics", "penalty_factor", "steps_per_period", "unknowns",
            "time_s", "time_ratio", "peak_memory_mib", "newton_iterations", "continuation_steps",
            "frequency_hz", "reference_hz", "error", "target", "target_met", "amplitude_gaps", "reference",
            "status", "settings_tried"]


# ---------------------------------------------------------------------- models
def load_model(name: str):
    """The model called ``name``: ``"oscillator"`` (one-DOF, m = k1 = 1, k2 = 4, gap 1) or
    ``"beam<n>"`` (the default beam with n elements, e.g. ``"beam21"``).

    Returns (model, oscillator or None).
    """
    import mmshbm

    from ..fe.oscillator import OneDofOscillator

    if not isinstance(name, str):
        raise TypeError(f"model must be a name such as 'beam21' or 'oscillator', got {name!r}")
    if name in ("oscillator", "one_dof", "onedof"):
        osc = OneDofOscillator(1.0, 1.0, 4.0, 1.0)
        return osc.model(), osc
    if name.startswith("beam") and name[4:].isdigit() and int(name[4:]) >= 1:
        return mmshbm.default_beam().model(int(name[4:])), None
    raise ValueError(f"unknown model {name!r}: use 'oscillator' or 'beam<n elements>' (e.g. 'beam21')")


# ---------------------------------------------------------------------- runs
@dataclass
class _Run:
    method: str
    options: dict
    frequency: float
    error: float
    seconds: float
    branch: object = field(repr=False, default=None)

    @property
    def ok(self) -> bool:
        return bool(np.isfinite(self.error))


def _run(model, method, amplitude, options, f_ref) -> _Run:
    t0 = time.perf_counter()
    try:
        branch = _backbone(model, method, amplitude, options)
    except (ArithmeticError, ValueError, np.linalg.LinAlgError) as err:
        log.info("%s %s failed: %s", method, options, err)
        return _Run(method, dict(options), math.nan, math.nan, time.perf_counter() - t0)
    seconds = time.perf_counter() - t0
    f = _reached_frequency(branch, amplitude)
    err = abs(f - f_ref) / f_ref if np.isfinite(f) else math.nan
    log.info("%s %s: f = %.9g Hz, error %.3g, %.3f s", method, options, f, err, seconds)
    return _Run(method, dict(options), f, err, seconds, branch)


def _meets(run: _Run, target: float) -> bool:
    return run.ok and run.error <= target


def _tune_ladder(model, method, amplitude, f_ref, target, ladder) -> tuple[_Run | None, list[_Run]]:
    """Walk ``ladder`` (list of option dicts, coarse to fine) until a rung and the next both
    meet the target; returns (chosen run or None, all runs)."""
    runs = []
    for options in ladder:
        runs.append(_run(model, method, amplitude, options, f_ref))
        if len(runs) >= 2 and _meets(runs[-2], target) and _meets(runs[-1], target):
            return runs[-2], runs
    if runs and _meets(runs[-1], target) and (len(runs) == 1 or not _meets(runs[-2], target)):
        return runs[-1], runs  # the finest rung meets it; nothing finer to confirm with
    return None, runs


def _most_accurate(runs: list[_Run]) -> _Run:
    finite = [r for r in runs if r.ok]
    return min(finite, key=lambda r: r.error) if finite else runs[-1]


# ---------------------------------------------------------------------- references
@dataclass
class _Reference:
    frequency: float
    label: str
    equal_h: bool = False


def _reference(model, osc, amplitude: float, target: float) -> _Reference:
    if osc is not None:
        return _Reference(float(osc.frequency(amplitude)), "closed form (one-DOF oscillator)")
    import mmshbm

    seed = mmshbm.backbone(model, harmonics=_EQUAL_H, max_amplitude=amplitude)
    f_seed = _reached_frequency(seed, amplitude)
    try:
        orbit = _exact_orbit(model, seed, amplitude)
    except (ArithmeticError, ValueError, np.linalg.LinAlgError, ImportError) as err:
        log.info("exact periodic orbit failed: %s", err)
        orbit = None
    if orbit is not None and orbit.converged:
        return _Reference(float(orbit.frequency), f"mmshbm.exact.periodic_orbit "
                                                  f"({orbit.n_contacts} contact(s) per period)")
    log.info("no converged exact orbit at %.4g m%s", amplitude,
             "" if orbit is None else f" ({orbit.n_contacts} contacts, residual {orbit.residual:.2e})")
    # converged in H? The branches of the starting mode's family (the default continuation)
    high = [_reached_frequency(mmshbm.backbone(model, harmonics=H, max_amplitude=amplitude), amplitude)
            for H in _HIGH_H]
    if all(np.isfinite(high)) and abs(high[1] - high[0]) <= 0.1 * target * abs(high[1]):
        return _Reference(high[1], f"MMS-HBM H={_HIGH_H[1]} (H={_HIGH_H[0]} agrees to "
                                   f"{abs(high[1] - high[0]) / high[1]:.1e})")
    ref = mmshbm.backbone(model, harmonics=_EQUAL_H, max_amplitude=amplitude, n_samples=_REFERENCE_N)
    f_ref = _reached_frequency(ref, amplitude)
    if not np.isfinite(f_ref):
        raise ValueError(f"no reference: MMS-HBM H={_EQUAL_H} does not reach {amplitude:g} m on this model")
    high_txt = ", ".join(f"H={H}: {f:.6g} Hz" for H, f in zip(_HIGH_H, high, strict=True))
    return _Reference(f_ref, f"equal H: MMS-HBM H={_EQUAL_H}, N={_REFERENCE_N} (no converged exact orbit; "
                             f"not converged in H: {high_txt}; H={_EQUAL_H} default N: {f_seed:.9g} Hz)",
                      equal_h=True)


def _exact_orbit(model, branch, amplitude):
    """Exact symmetric orbit at ``amplitude`` started from the last point of ``branch``."""
    from ..methods import exact

    if len(branch) == 0:
        return None
    i = len(branch) - 1
    _, q = branch.time_signals(i, n_samples=512)
    j = int(np.argmax(-model.stop_side * q[model.contact_dof]))
    guess = (q[model.l, j], 0.5 / float(branch.frequency[i]))
    return exact.periodic_orbit(model, amplitude, guess)


# ---------------------------------------------------------------------- ladders
def _ladders(method: str, quick: bool, beam: bool, equal_h: bool) -> list[list[dict]]:
    q = 1 if quick else 0
    resolution = method_info(method).resolution
    if resolution == "harmonics":
        if equal_h:
            return [[{"harmonics": _EQUAL_H}] + [{"harmonics": _EQUAL_H, "n_samples": n} for n in (256, 512)]]
        return [[{"harmonics": H} for H in _H_LADDER[q]]]
    if resolution == "harmonics and penalty":
        Hs = (_EQUAL_H,) if equal_h else _PENALTY_H[q]
        if equal_h:
            return [[{"harmonics": _EQUAL_H, "penalty_factor": f} for f in _PENALTY_FACTORS[q]]]
        return [[{"harmonics": H, "penalty_factor": f} for H in Hs] for f in _PENALTY_FACTORS[q]]
    if resolution == "time steps":
        steps = _BEAM_STEPS[q] if beam else _STEPS[q]
        return [[{"steps_per_period": s} for s in steps]]
    raise ValueError(f"unknown method {method!r}; choose from {sorted(METHOD_NAMES)}")


def _setting(method: str, options: dict) -> str:
    parts = []
    if is_harmonic_balance(method):
        parts.append(f"H={options.get('harmonics', 5)}")
    if "n_samples" in options:
        parts.append(f"N={options['n_samples']}")
    if "penalty_factor" in options:
        parts.append(f"k_p={options['penalty_factor']:.0e} k_c")
    if "steps_per_period" in options:
        parts.append(f"{options['steps_per_period']} steps/period")
    return ", ".join(parts)


# ---------------------------------------------------------------------- measurement
#: amplitude of the comparison (gaps) per model kind. The oscillator: 2 gaps (closed form
#: everywhere). The beam: 1.5 gaps, below the 5:1 internal resonance (5 x 54.75 Hz, 4 %
#: below f2 = 286.1 Hz); at 2 gaps the H = 5 branch sits on that resonance (57.06 Hz:
#: where it enters the tongue, which it climbs to 3.1 gaps), and 3 gaps is inside the
#: excursion (docs/benchmarks.md, "What the beam does above grazing").
DEFAULT_AMPLITUDE_GAPS = {"oscillator": 2.0, "beam": 1.5}


def default_amplitude(model: str) -> float:
    """The comparison amplitude (gaps) of :func:`compare_methods` for ``model``."""
    return DEFAULT_AMPLITUDE_GAPS["oscillator" if load_model(model)[1] is not None else "beam"]


def compare_methods(model: str = "beam21", amplitude_gaps: float | None = None, target: float = 1e-4,
                    methods=None, repeats: int = 3,
                    quick: bool = False) -> list[dict]:
    """Tune each method to ``target`` and measure its cost (module docstring).

    Parameters
    ----------
    model : str
        ``"beam21"`` (default beam, 21 elements), ``"beam8"``, any ``"beam<n>"``, or
        ``"oscillator"`` (one-DOF, closed-form reference).
    amplitude_gaps : float, optional
        Amplitude of the comparison in gaps (> 1: above grazing); default
        :data:`DEFAULT_AMPLITUDE_GAPS` (oscillator 2, beam 1.5).
    target : float
        Relative frequency error to reach, in (0, 1).
    methods : sequence of {"mmshbm", "penalty", "shooting"}, optional
        Default all three (:data:`METHOD_NAMES`). A method that is not installed is
        skipped with a warning.
    repeats : int
        Timed whole-backbone runs per method (the fastest counts), >= 1.
    quick : bool
        Shorter ladders (for tests and CI).

    Returns
    -------
    list of dict
        One row per method with the keys of :data:`_COLUMNS`: ``setting`` (the chosen
        resolution), ``unknowns``, ``time_s``, ``time_ratio`` (time / MMS-HBM's time),
        ``peak_memory_mib``, ``newton_iterations``, ``continuation_steps``,
        ``frequency_hz``, ``reference_hz``, ``error`` (relative), ``target_met``,
        ``reference`` (what the reference is), ``status`` and ``settings_tried``.
    """
    from .. import _validate as check

    if methods is None:
        methods = tuple(METHOD_NAMES)
    if isinstance(methods, str):
        methods = (methods,)
    methods = tuple(methods)
    if not methods:
        raise ValueError("methods must name at least one method")
    for m in methods:
        if m not in METHOD_NAMES:
            raise ValueError(f"unknown method {m!r}; choose from {sorted(METHOD_NAMES)}")
    if amplitude_gaps is None:
        amplitude_gaps = default_amplitude(model)
    amplitude_gaps = check.positive("amplitude_gaps", amplitude_gaps)
    target = check.positive("target", target)
    if not target < 1:
        raise ValueError(f"target must be a relative error in (0, 1), got {target!r}")
    repeats = check.integer("repeats", repeats, minimum=1)
    mdl, osc = load_model(model)
    amplitude = amplitude_gaps * mdl.gap
    ref = _reference(mdl, osc, amplitude, target)
    log.info("reference %.12g Hz: %s", ref.frequency, ref.label)

    rows = []
    for method in methods:
        if not _available(method):
            log.warning("%s is not available: skipped", method)
            continue
        runs, candidates = [], []
        for ladder in _ladders(method, quick, osc is None, ref.equal_h):
            chosen, tried = _tune_ladder(mdl, method, amplitude, ref.frequency, target, ladder)
            runs += tried
            if chosen is not None:
                candidates.append(chosen)
        met = bool(candidates)
        pick = min(candidates, key=lambda r: r.seconds) if met else _most_accurate(runs)
        seconds, peak, branch = _measure(mdl, method, amplitude, pick.options, repeats)
        solver = branch.solver
        rows.append({
            "model": model, "method": method, "setting": _setting(method, pick.options),
            "harmonics": int(pick.options.get("harmonics", 0)) if is_harmonic_balance(method) else 0,
            "penalty_factor": pick.options.get("penalty_factor", math.nan),
            "steps_per_period": int(pick.options.get("steps_per_period", 0)),
            "n_samples": int(pick.options.get("n_samples", 0)),
            "unknowns": int(solver.n_unknowns), "time_s": seconds, "time_ratio": math.nan,
            "peak_memory_mib": peak, "newton_iterations": int(np.sum(branch.newton_iterations)),
            "continuation_steps": max(len(branch) - 1, 0), "frequency_hz": pick.frequency,
            "reference_hz": ref.frequency, "error": pick.error, "target": target, "target_met": met,
            "amplitude_gaps": amplitude_gaps, "reference": ref.label, "status": branch.status,
            "settings_tried": len(runs),
        })
    # the times relative to the method the baselines are compared with
    base = next((r["time_s"] for r in rows if not method_info(r["method"]).baseline), None)
    if base:
        for r in rows:
            r["time_ratio"] = r["time_s"] / base
    return rows


def _available(method: str) -> bool:
    import importlib

    from ..methods.registry import METHODS

    try:
        importlib.import_module(METHODS[method].split(":")[0])
    except ImportError:
        return False
    return True


# ---------------------------------------------------------------------- output
def format_table(rows: list[dict]) -> str:
    """Markdown table of :func:`compare_methods` rows, with the reference underneath."""
    if not rows:
        return "(no results)"
    head = ("| method | setting | unknowns | time (ms) | × MMS-HBM | peak mem (MiB) | Newton it. | steps "
            "| f (Hz) | rel. error | target met |")
    lines = [head, "|" + "---|" * 11]
    for r in rows:
        ratio = "" if not np.isfinite(r["time_ratio"]) else f"{r['time_ratio']:.1f}"
        lines.append(
            f"| {METHOD_NAMES.get(r['method'], r['method'])} | {r['setting']} | {r['unknowns']} "
            f"| {1e3 * r['time_s']:.1f} | {ratio} | {r['peak_memory_mib']:.2f} | {r['newton_iterations']} "
            f"| {r['continuation_steps']} | {r['frequency_hz']:.9g} | {r['error']:.2e} "
            f"| {'yes' if r['target_met'] else 'no'} |")
    r0 = rows[0]
    lines.append("")
    lines.append(f"Model {r0['model']}, amplitude {r0['amplitude_gaps']:g} gaps, target {r0['target']:g} "
                 f"relative frequency error; reference {r0['reference_hz']:.12g} Hz: {r0['reference']}. "
                 "Time: fastest of the repeats, whole backbone from half a gap, kernels compiled.")
    return "\n".join(lines)


def write_results(rows: list[dict], out_dir) -> list[Path]:
    """Write ``bench.csv`` (all columns) and ``bench.md`` (:func:`format_table`) into
    ``out_dir``; returns the two paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    csv_path, md_path = out / "bench.csv", out / "bench.md"
    with csv_path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=_COLUMNS, extrasaction="ignore")
        writer.writeheader()
        for r in rows:
            writer.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items()})
    md_path.write_text(format_table(rows) + "\n")
    return [csv_path, md_path]
