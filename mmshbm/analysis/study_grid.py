"""The grid of a study: the run descriptions (:class:`~mmshbm.analysis.runspec.RunSpec`)
of every combination of harmonics × elements × method × model parameters × samples, and
Latin-hypercube samples of model parameters (:func:`monte_carlo`). Validation only:
nothing is computed here (:func:`mmshbm.analysis.studies.run_study` runs the grid)."""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import fields, replace
from pathlib import Path

import numpy as np

from .. import _validate as check
from .runspec import RunSpec, matrix_source

__all__ = ["grid_specs", "monte_carlo", "AXES"]

#: the grid axes of their own (not model parameters nor options)
AXES = ("method", "elements", "harmonics")
_AXES = AXES


def grid_specs(beam=None, *, model=None, harmonics=(1, 3, 5), elements=None, methods=("mmshbm",),
               params=None, samples=None, grading=10.0, max_amplitude=None, unit="m",
               **options) -> list[RunSpec]:
    """The :class:`RunSpec` list of :func:`run_study` (validated, nothing computed)."""
    from ..fe.beam import TimoshenkoBeam, default_beam
    from ..methods.registry import METHODS
    from ..model.model import Model

    unit = _unit(unit)
    if max_amplitude is not None:
        max_amplitude = check.positive("max_amplitude", max_amplitude)
    hs = _int_list("harmonics", harmonics, 1)
    for m in _list("methods", methods):
        if m not in METHODS:
            raise ValueError(f"unknown method {m!r}; choose from {sorted(METHODS)}")
    params = dict(params or {})
    for name, values in params.items():
        if name in _AXES:
            raise ValueError(f"{name!r} is a grid axis of its own, not a parameter")
        params[name] = _list(f"params[{name!r}]", values)
    samples = _samples(samples, params)
    beam_fields = {f.name for f in fields(TimoshenkoBeam)}

    if model is not None:
        if beam is not None:
            raise ValueError("pass either beam or model, not both")
        if elements is not None:
            raise ValueError("elements applies to beams only, not to a user model")
        bad = [k for k in (*params, *samples) if k in (beam_fields | {"grading"}) - {"gap"}]
        if bad:
            raise ValueError(f"a user model can vary only 'gap' of its own parameters, got {bad}")
        if isinstance(model, str | Path):
            if not Path(model).is_file():
                raise ValueError(f"model file {str(model)!r} does not exist")
            base = {"file": str(Path(model).resolve())}
        elif isinstance(model, Model):
            base = matrix_source(model)
        else:
            raise TypeError(f"model must be an mmshbm.Model or a .npz path, got {type(model).__name__}")
        axes = [("method", list(methods)), ("harmonics", hs)]
    else:
        beam = default_beam() if beam is None else beam
        if not isinstance(beam, TimoshenkoBeam):
            raise TypeError(f"beam must be a TimoshenkoBeam, got {type(beam).__name__}")
        check.positive("grading", grading)
        ns = _int_list("elements", (8, 21) if elements is None else elements, 1)
        axes = [("method", list(methods)), ("elements", ns), ("harmonics", hs)]
    axes += list(params.items())
    if samples:
        axes.append(("sample", list(range(len(next(iter(samples.values())))))))

    specs = []
    for index, combo in enumerate(itertools.product(*(v for _, v in axes))):
        coords = dict(zip((k for k, _ in axes), combo, strict=True))
        if samples:
            coords.update({k: v[coords["sample"]] for k, v in samples.items()})
        run_options = dict(options)
        if model is not None:
            source = dict(base)
            if "gap" in coords:
                source["gap"] = check.non_negative("gap", coords["gap"])
        else:
            changes = {k: v for k, v in coords.items() if k in beam_fields}
            try:
                run_beam = replace(beam, **changes)
            except (TypeError, ValueError) as err:
                raise ValueError(f"bad beam parameter in {changes}: {err}") from None
            source = {"beam": {f.name: getattr(run_beam, f.name) for f in fields(TimoshenkoBeam)},
                      "n_elements": coords["elements"], "grading": float(coords.get("grading", grading))}
        for k, v in coords.items():
            if k not in _AXES and k not in beam_fields and k not in ("grading", "sample"):
                run_options[k] = v
        specs.append(RunSpec(index=index, coords=coords, source=source, harmonics=coords["harmonics"],
                             method=coords["method"], max_amplitude=max_amplitude, unit=unit,
                             options=run_options))
    return specs


def monte_carlo(n: int, ranges: Mapping[str, tuple[float, float]], seed: int = 0) -> dict:
    """``n`` parameter sets drawn uniformly and independently in ``ranges`` (a Latin
    hypercube: every parameter's range is cut into n equal strata, one draw per stratum),
    for ``run_study(samples=...)``.

    Parameters
    ----------
    n : int
        Number of samples.
    ranges : mapping of str to (low, high)
        E.g. ``{"gap": (0.5e-3, 2e-3), "E": (2.0e11, 2.2e11), "rho": (7700, 7900)}`` (SI).
    seed : int
        Seed of :func:`numpy.random.default_rng`: the same seed gives the same samples.

    Returns
    -------
    dict of str to list of float
    """
    n = check.integer("n", n, minimum=1)
    rng = np.random.default_rng(check.integer("seed", seed, minimum=0))
    out = {}
    for name, bounds in dict(ranges).items():
        try:
            lo, hi = (float(v) for v in bounds)
        except (TypeError, ValueError):
            raise ValueError(f"ranges[{name!r}] must be (low, high), got {bounds!r}") from None
        if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
            raise ValueError(f"ranges[{name!r}] must be finite with low <= high, got {bounds!r}")
        strata = (rng.permutation(n) + rng.random(n)) / n
        out[name] = [float(v) for v in lo + (hi - lo) * strata]
    return out


def _unit(unit: str) -> str:
    if unit not in ("m", "gap"):
        raise ValueError(f"unit must be 'm' or 'gap', got {unit!r}")
    return unit


def _samples(samples, params: dict) -> dict:
    """Validated ``samples``: names not grid axes nor in ``params``, equal lengths."""
    samples = dict(samples or {})
    n = None
    for name, values in samples.items():
        if name in _AXES or name == "sample":
            raise ValueError(f"{name!r} is a grid axis of its own, not a sampled parameter")
        if name in params:
            raise ValueError(f"{name!r} is both a grid parameter and a sampled one")
        samples[name] = _list(f"samples[{name!r}]", values)
        if n is not None and len(samples[name]) != n:
            raise ValueError(f"samples must have equal lengths: {name!r} has {len(samples[name])} values, "
                             f"not {n}")
        n = len(samples[name])
    return samples


def _list(name: str, values) -> list:
    if isinstance(values, str | bytes) or not isinstance(values, Sequence | np.ndarray):
        raise TypeError(f"{name} must be a sequence of values, got {values!r}")
    values = list(values)
    if not values:
        raise ValueError(f"{name} is empty")
    return [v.item() if isinstance(v, np.generic) else v for v in values]


def _int_list(name: str, values, minimum: int) -> list[int]:
    return [check.integer(name, v, minimum=minimum) for v in _list(name, values)]
