"""The run behind the methods' entry points, shared by :func:`~mmshbm.methods.backbone.backbone`
and :func:`~mmshbm.methods.frequency_response.frequency_response`.

Each entry point validates its own arguments and builds its continuation problem; this
module holds what they have in common:

- validation: the model, the method name, H, the callback, option names, file paths;
- the continuation options: the caller's continuation fields taken out of ``**options``,
  over the entry point's defaults, its bounds under the caller's;
- the run (:func:`run`): checkpointing to a JSON-lines file and resuming from one
  (:mod:`mmshbm.core.checkpoint`), BLAS limited to one thread, the pseudo-arclength driver,
  the wall time;
- annotation: the grazing point (the first point where a stop carries force), the named
  internal resonances of a backbone, the bifurcations of a forced response;
- the metadata every result records (model, method, H, N, options, timing, versions).
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import inspect
import logging
import platform
import time
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .. import _validate as check
from .._threads import blas_limit
from ..core.checkpoint import _plain as jsonable
from ..core.continuation import ContinuationOptions, ContinuationResult, continue_branch
from ..core.special_points import SpecialPoint
from ..core.status import Status
from ..family.follower import default_events
from ..model.model import Model

__all__ = ["CONTINUATION_FIELDS", "Run", "run", "jsonable", "continuation_options", "check_option_names",
           "check_is_nonlinear", "checkpoint_header", "mark_grazing", "run_metadata"]

log = logging.getLogger(__name__)

#: the names of :class:`ContinuationOptions`' fields: the continuation part of ``**options``
CONTINUATION_FIELDS = frozenset(f.name for f in dataclasses.fields(ContinuationOptions))
#: header entries a resumed run must share with its checkpoint file (before the ``extra`` ones)
_RESUME_KEYS = ("method", "n_unknowns", "model", "solver", "method_options")
#: how a resume mismatch names a header entry (or an entry of its ``solver`` settings): the
#: argument of ``mmshbm.backbone`` / ``frequency_response`` that sets it
SETTING_NAMES = {
    "H": "harmonics (H)", "N": "n_samples (N)", "r": "r", "mode": "mode",
    "penalty_stiffness": "penalty_stiffness", "steps_per_period": "steps_per_period",
    "method": "method", "model": "the model's matrices, contact DOF, gap or stop side",
    "n_unknowns": "the number of unknowns", "pole_scaling": "the scaling of the pole unknowns",
}


# ---------------------------------------------------------------------- validation
def check_model(model) -> None:
    """TypeError unless ``model`` is a :class:`~mmshbm.model.Model`."""
    if not isinstance(model, Model):
        raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")


def check_is_nonlinear(model: Model, what: str) -> None:
    """ValueError when ``model`` has no nonlinearity (no unilateral contact, no friction
    contact, no element of :mod:`mmshbm.elements`): ``what`` (a backbone, a forced response)
    of a linear structure is linear and needs no continuation."""
    if model.contacts or model.friction or model.elements:
        return
    hints = {"backbone": "a backbone of a linear model is its linear mode, at every amplitude: "
                         "model.linear_modes(n) gives its frequencies (Hz) and shapes",
             "forced response": "the forced response of a linear model is linear: "
                                "(K - Ω² M + iΩ C)⁻¹ F̂ at each frequency, with no continuation"}
    raise ValueError(f"the model has no contact and no nonlinear element (no stop, no friction, no "
                     f"element): {hints[what]}; add a stop with Model.from_matrices(M, K, contact_dof=..., "
                     "gap=...), friction with model.with_friction(...) or an element with "
                     "model.with_element(mmshbm.elements.CubicSpring(...))")


def check_method(method, methods) -> None:
    """ValueError unless ``method`` is one of the names ``methods``."""
    if not isinstance(method, str) or method not in methods:
        raise ValueError(f"unknown method {method!r}; choose one of {sorted(methods)}")


def check_harmonics(method: str, harmonics) -> None:
    """H >= 1 for the harmonic-balance methods (shooting has none)."""
    from .._method_info import is_harmonic_balance

    if is_harmonic_balance(method):
        check.integer("harmonics", harmonics, minimum=1)


def check_callback(callback) -> None:
    if callback is not None and not callable(callback):
        raise TypeError(f"callback must be callable, got {type(callback).__name__} {callback!r}")


def check_option_names(problem_class, options: Mapping, *, what: str, skip: int = 1,
                       extra_names=()) -> list[str]:
    """TypeError naming every key of ``options`` that the constructor of ``problem_class``
    does not take (after its first ``skip`` parameters: the model, the force), with the
    nearest valid name among those, the continuation options and ``extra_names``.

    Returns
    -------
    list of str
        The option names the constructor takes.
    """
    valid, var_keyword = _parameter_names(problem_class, skip)
    valid = list(valid)
    if var_keyword:
        return valid
    unknown = [k for k in options if k not in valid]
    if unknown:
        everything = sorted(set(valid) | CONTINUATION_FIELDS | set(extra_names))
        hints = []
        for name in unknown:
            close = difflib.get_close_matches(name, everything, n=1)
            hints.append(f"{name!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
        raise TypeError(f"unknown option{'s' if len(unknown) > 1 else ''} {', '.join(hints)} for {what}; "
                        f"method options: {valid}; continuation options: {sorted(CONTINUATION_FIELDS)}")
    return valid


@functools.lru_cache(maxsize=64)
def _parameter_names(problem_class, skip: int) -> tuple[tuple[str, ...], bool]:
    """(names of the keyword-capable parameters of ``problem_class``'s constructor after its
    first ``skip``, whether it takes ``**kwargs``): one signature inspection per class."""
    params = list(inspect.signature(problem_class).parameters.values())[skip:]
    return (tuple(p.name for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)),
            any(p.kind == p.VAR_KEYWORD for p in params))


def path_argument(name: str, value) -> Path | None:
    """``value`` as a Path (None stays None); TypeError for anything but a non-empty str or Path."""
    if value is None:
        return None
    if not isinstance(value, str | Path) or str(value) == "":
        raise TypeError(f"{name} must be a file path (str or Path), got {type(value).__name__} {value!r}")
    return Path(value)


def continuation_options(options: dict, bounds: Mapping,
                         defaults: Mapping | None = None) -> ContinuationOptions:
    """The run's :class:`ContinuationOptions`: the continuation fields taken out of
    ``options`` (the rest are method options) over ``defaults``, with ``bounds`` (name ->
    (lo, hi)) under the caller's own ``bounds`` option."""
    cont = {**dict(defaults or {}), **{k: options.pop(k) for k in list(options) if k in CONTINUATION_FIELDS}}
    cont["bounds"] = {**dict(bounds), **dict(cont.get("bounds", {}))}
    key = _options_key(cont)
    if key is None:
        return ContinuationOptions(**cont)
    valid = _VALIDATED.get(key)
    if valid is None:
        valid = ContinuationOptions(**cont)
        if len(_VALIDATED) >= _VALIDATED_KEPT:
            _VALIDATED.clear()
        _VALIDATED[key] = valid
    # the validated fields of the same values, in an object of this run's own (its own bounds dict)
    out = object.__new__(ContinuationOptions)
    out.__dict__.update(valid.__dict__)
    object.__setattr__(out, "bounds", dict(valid.bounds))
    return out


#: ContinuationOptions validated before, by :func:`_options_key` of the fields given
_VALIDATED: dict = {}
_VALIDATED_KEPT = 64
#: the types of the field values (and of the bounds' pairs' entries) whose options are kept
_KEYED = frozenset({float, int, str, bool})


def _options_key(cont: dict) -> tuple | None:
    """What fixes the :class:`ContinuationOptions` of the fields ``cont`` (the bounds in their
    order, which sets the order they are tested in): each name with its value's type and
    repr (-0.0 is not 0.0, 1 is not 1.0); None where a value is of another type (a list, an
    array, a NumPy scalar: validated every time)."""
    key = []
    for name, value in cont.items():
        if name == "bounds":
            for bound, pair in value.items():
                if type(bound) is not str or type(pair) is not tuple or len(pair) != 2 \
                        or type(pair[0]) not in _KEYED or type(pair[1]) not in _KEYED:
                    return None
                key.append(("bounds", bound, type(pair[0]), repr(pair[0]), type(pair[1]), repr(pair[1])))
        elif type(value) in _KEYED:
            key.append((name, type(value), repr(value)))
        else:
            return None
    return tuple(key)


# ---------------------------------------------------------------------- checkpoints
def checkpoint_header(model: Model, method: str, problem, options: dict, **extra) -> dict:
    """What fixes the branch: a resumed run must agree on all of it (the entries of
    ``extra`` included, e.g. a forced response's excitation)."""
    from ..core.checkpoint import model_fingerprint

    resolved = problem.solver_settings()
    return {"method": method, "n_unknowns": int(problem.n_unknowns), "model": model_fingerprint(model),
            "model_description": model.description, "solver": resolved,
            "method_options": jsonable({k: v for k, v in options.items()
                                        if k not in ("harmonics", "n_samples", "r", "mode")}),
            **problem.state_convention(), **jsonable(extra)}


def check_resumable(stored: dict, current: dict, path) -> None:
    """ValueError naming every entry of the run's configuration (``current``, a
    :func:`checkpoint_header`; the model's description left out) that differs from the
    file's (:func:`~mmshbm.core.checkpoint.header_differences`: H, N, method, options...)."""
    from ..core.checkpoint import header_differences

    keys = _RESUME_KEYS + tuple(k for k in current if k not in _RESUME_KEYS and k != "model_description")
    differences = header_differences(stored, current, keys, names=SETTING_NAMES,
                                     by_entry=("solver", "method_options"), fingerprints=("model",),
                                     last=("n_unknowns",))
    if differences:
        raise ValueError(f"cannot resume from {str(path)!r}: this run's settings differ from the file's: "
                         f"{'; '.join(differences)}; resume with the file's settings, or start a new run "
                         "without resume")


def _finished(previous, copts: ContinuationOptions) -> bool:
    """True when the file's branch ended on a bound that still applies."""
    if not previous.terminal:
        return False
    terminal = Status.parse(previous.terminal)
    if terminal.kind != Status.BOUND:
        return terminal.kind == Status.START_OUTSIDE
    name = terminal.detail
    stored = previous.header.get("continuation", {}).get("bounds", {}).get(name)
    now = dict(copts.bounds).get(name)
    return stored is not None and now is not None and [float(b) for b in stored] == [float(b) for b in now]


def _finished_result(state, status) -> ContinuationResult:
    recs = state.records
    return ContinuationResult(
        u=np.array(state.u), records={k: np.array([r[k] for r in recs]) for k in recs[0]},
        newton_iterations=np.array(state.newton_iterations, dtype=int),
        step_size=np.array(state.step_size, dtype=float), residual_histories=state.residual_histories,
        special_points=list(state.special_points) + [SpecialPoint("endpoint", len(state.u) - 1)],
        status=Status.parse(status),
        tangent=state.tangent, next_ds=state.ds, steps=state.steps)


# ---------------------------------------------------------------------- the run
@dataclasses.dataclass
class Run:
    """A finished continuation run.

    Attributes
    ----------
    result : ContinuationResult
        The driver's result (restored points included on resume).
    elapsed_s : float
        Wall time (s) of the run.
    checkpoint, resumed_from : Path or None
        The checkpoint file written, and the one resumed from.
    resumed_points : int
        Points taken from ``resumed_from``.
    """

    result: ContinuationResult
    elapsed_s: float
    checkpoint: Path | None = None
    resumed_from: Path | None = None
    resumed_points: int = 0

    def metadata(self) -> dict:
        """The checkpoint entries of the result's metadata (none when neither file was used)."""
        out = {}
        if self.checkpoint is not None:
            out["checkpoint"] = str(self.checkpoint)
        if self.resumed_from is not None:
            out["resumed_from"] = str(self.resumed_from)
            out["resumed_points"] = self.resumed_points
        return out


def run(problem, copts: ContinuationOptions, start, *, callback=None, progress=None, checkpoint=None,
        resume=None, header: dict | None = None, header_extra: Mapping | None = None, close=()) -> Run:
    """Continue ``problem`` from ``start()`` (a callable returning the first point and tangent,
    called only when the run does not resume) with ``copts``.

    Parameters
    ----------
    checkpoint : Path, optional
        Write every converged point to this file as it comes (:mod:`mmshbm.core.checkpoint`).
    resume : Path, optional
        Go on from the last point of this checkpoint file, whose ``header`` must agree with
        this run's (:func:`checkpoint_header`); a file whose branch ended on a bound that
        still applies is returned as it is.
    header : dict
        :func:`checkpoint_header` of this run (needed with ``checkpoint`` or ``resume``).
    header_extra : dict, optional
        Further entries of the checkpoint file's header (not compared on resume).
    callback, progress
        As :func:`~mmshbm.core.continuation.continue_branch`.
    close : iterable
        Objects with a ``close()`` (progress bars) closed when the run ends, however it ends.
    """
    from ..core.checkpoint import CheckpointWriter, read_checkpoint

    writer, state, restored, previous = None, None, [], None
    try:
        if resume is not None:
            previous = read_checkpoint(resume)
            check_resumable(previous.header, header, resume)
            state = previous.state()
            restored = previous.points
            log.info("resuming %s from point %d of %s", header["method"], len(restored) - 1, resume)
        if checkpoint is not None:
            continuation = _options_record(copts)
            writer = CheckpointWriter(checkpoint, {**header, "continuation": continuation,
                                                   **dict(header_extra or {})}, restored)
        t0 = time.perf_counter()
        if previous is not None and _finished(previous, copts):
            res = _finished_result(state, previous.terminal)
        else:
            with blas_limit():  # small dense solves: one BLAS thread unless the user chose (mmshbm._threads)
                u0, t0_ = (None, None) if state else start()
                res = continue_branch(problem, u0, t0_, copts, callback=callback, progress=progress,
                                      resume=state, on_point=writer.point if writer is not None else None,
                                      events=default_events(copts, continue_branch))
        if writer is not None:
            writer.end(res.status)
        elapsed = time.perf_counter() - t0
    finally:
        for item in close:
            if item is not None:
                item.close()
        if writer is not None:
            writer.close()
    return Run(res, elapsed, checkpoint, resume, len(restored))


# ---------------------------------------------------------------------- annotation
def mark_grazing(special: list, contact_force_max, amplitude, gap: float) -> list:
    """``special`` with a "grazing" point after "start": the first point, past the first,
    where a stop carries force (``contact_force_max`` > 0). Where the force is not
    recorded (all NaN), the first point whose amplitude passes the gap (> gap·(1 + 1e-9)).
    None on a model whose smallest gap is 0 (a stop touched from the start).

    The force, not the amplitude, says where a stop is first touched: the amplitude is
    that of ``model.amplitude_dof``, which with several contacts, a clearance or a forced
    response need not be the contact DOF whose gap is ``gap``.
    """
    force = np.asarray(contact_force_max, dtype=float)
    if not gap > 0:
        hits = np.zeros(0, dtype=int)
    elif np.isfinite(force).any():
        hits = np.flatnonzero(force > 0)
    else:
        hits = np.flatnonzero(np.asarray(amplitude, dtype=float) > gap * (1 + 1e-9))
    special = list(special)
    if len(hits) and hits[0] > 0:
        special.insert(1, SpecialPoint("grazing", int(hits[0])))
    return special


def name_internal_resonances(problem, rec: dict, special: list) -> list:
    """``special`` with the internal resonances that the backbone's modal shares name
    (:func:`~mmshbm.core.resonances.internal_resonances`), in index order."""
    from ..core.resonances import internal_resonances

    if "modal_shares" in rec and problem.tracked_frequencies is not None:
        shares = rec["modal_shares"]
        if np.ndim(shares) == 3 and np.shape(shares)[1] == 1 and problem.mode == 1:
            named = []  # the starting mode is the only one tracked: no partner to resonate with
        else:
            named = internal_resonances(rec["frequency"], shares, problem.tracked_frequencies, problem.mode)
        special = sorted(special + named, key=lambda s: (s[1], s[0] == "endpoint"))
    return special


def name_bifurcations(rec: dict, special: list, n: int) -> tuple[np.ndarray, list]:
    """(stable (n,), special) from the recorded Floquet multipliers (``rec["floquet"]``):
    :func:`~mmshbm.methods.mms.stability.classify`, the folds of the continuation kept as
    such; all stable and ``special`` unchanged when none were recorded."""
    from .mms.stability import classify

    stable = np.ones(n, dtype=bool)
    if "floquet" in rec and n:
        folds = [p.index for p in special if p.kind == "fold"]
        stable, bifurcations = classify(np.asarray(rec["floquet"]), trivial=0, folds=folds)
        special = special[:-1] + bifurcations + special[-1:]
        special.sort(key=lambda p: (p.index, p.kind == "endpoint"))
    return stable, special


# ---------------------------------------------------------------------- metadata
def _options_record(copts: ContinuationOptions) -> dict:
    """``jsonable(dataclasses.asdict(copts))``: its fields read once (the same dict when no
    field holds a dataclass, as none does: asdict would copy what jsonable copies again)."""
    exact = type(copts) is ContinuationOptions
    names = _OPTION_NAMES if exact else [f.name for f in dataclasses.fields(copts)]
    values = {name: getattr(copts, name) for name in names}
    if any(type(v) not in _PLAIN and dataclasses.is_dataclass(v) for v in values.values()):
        return jsonable(dataclasses.asdict(copts))
    return jsonable(values)


#: the field names of ContinuationOptions, in order; the types no dataclass has
_OPTION_NAMES = tuple(f.name for f in dataclasses.fields(ContinuationOptions))
_PLAIN = frozenset({float, int, str, bool, dict, tuple, list, type(None)})


#: the interpreter's version (as ``platform.python_version()`` gives it, once)
_PYTHON = platform.python_version()


def run_metadata(model: Model, method: str, problem, options: dict, copts: ContinuationOptions, done: Run,
                 **fields) -> dict:
    """The metadata of a result: the model's description, method, H, N, the entry point's
    own ``fields`` (amplitudes, frequency range, excitation, ...), method and continuation
    options, wall time, versions, and the checkpoint files used."""
    return {"model": model.description, "method": method, "harmonics": int(problem.H),
            "n_samples": int(problem.N), **fields, "method_options": jsonable(options),
            "continuation": _options_record(copts), "elapsed_s": done.elapsed_s,
            "python": _PYTHON, "numpy": np.__version__, **done.metadata(), **problem.state_convention()}
