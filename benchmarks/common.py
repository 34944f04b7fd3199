"""Shared pieces of the asv suites: models, references, warm-up and skip rules.

Numba kernels are compiled (or loaded from numba's cache) in ``setup`` through
:func:`warm_up`, so no timed sample contains compilation. Every combination that is
hopeless on purpose raises ``NotImplementedError`` in ``setup`` (asv records it as
skipped) with the reason in :data:`SKIP_REASONS`.
"""

from __future__ import annotations

import functools
import importlib

import numpy as np

#: highest harmonic H of the harmonic-balance methods
HARMONICS = (1, 3, 5, 9, 15)
#: element counts of the default beam
ELEMENTS = (8, 21, 100, 1000)
#: the models of the whole-backbone suites
MODELS = ("oscillator", "beam8", "beam21")
#: time steps per period of shooting
STEPS = (64, 128, 256)
#: amplitude of the whole backbones and of the tracked errors, in gaps
AMPLITUDE_GAPS = 2.0

#: why a combination is skipped (measured on the 2-core development machine)
SKIP_REASONS = {
    "shooting-large": "shooting integrates n_l + 1 tangent vectors over every step: a backbone on "
                      "100 elements takes ~45 s, on 1000 elements hours",
    "shooting-iteration": "one shooting Newton iteration on 1000 elements propagates 2001 tangent "
                          "vectors through every step",
    "penalty-1000-high": "penalty-HBM on 1000 elements with H >= 9: 23 s (H = 9) and 53 s (H = 15) per "
                         "backbone to 2 gaps (12 001+ unknowns, 230-280 points), too long for every "
                         "asv sample (H <= 5: ~2 s, timed)",
}


def available(method: str) -> bool:
    """Whether ``method``'s module imports (shooting may be missing on old commits)."""
    from mmshbm.methods.registry import METHODS

    try:
        importlib.import_module(METHODS[method].split(":")[0])
    except ImportError:
        return False
    return True


def require(method: str) -> None:
    """Skip (NotImplementedError) when ``method`` is not available in this commit."""
    if not available(method):
        raise NotImplementedError(f"{method} is not available in this version")


@functools.cache
def model(name: str):
    """``"oscillator"`` or ``"beam<n>"`` -> Model (cached per process)."""
    from mmshbm.analysis.benchmarking import load_model

    return load_model(name)[0]


def beam_name(elements: int) -> str:
    return f"beam{elements}"


def options(method: str, harmonics: int | None = None, steps: int | None = None) -> dict:
    """Keyword options of ``mmshbm.backbone`` / ``make_problem`` for a method."""
    if method == "shooting":
        return {} if steps is None else {"steps_per_period": steps}
    return {"harmonics": harmonics}


@functools.cache
def warm_up(method: str) -> None:
    """Compile (or load from cache) every kernel ``method`` uses: a short backbone of the
    one-DOF oscillator."""
    import mmshbm

    require(method)
    kw = {"steps_per_period": 64} if method == "shooting" else {"harmonics": 3}
    mmshbm.backbone(model("oscillator"), method=method, max_amplitude=1.5, **kw)


def backbone(name: str, method: str, harmonics: int | None = None, steps: int | None = None,
             amplitude_gaps: float = AMPLITUDE_GAPS):
    """The whole backbone of model ``name`` from half a gap up to ``amplitude_gaps``."""
    import mmshbm

    m = model(name)
    kw = options(method, harmonics, steps)
    return mmshbm.backbone(m, method=method, max_amplitude=amplitude_gaps * m.gap, **kw)


def check_feasible(name: str, method: str, harmonics: int | None = None,
                   single_iteration: bool = False) -> None:
    """Raise NotImplementedError for the combinations in :data:`SKIP_REASONS`.

    ``single_iteration``: only one Newton iteration is timed (affordable for every
    harmonic-balance case and for shooting up to 100 elements)."""
    require(method)
    n = int(name[4:]) if name.startswith("beam") else 0
    if single_iteration:
        if method == "shooting" and n >= 1000:
            raise NotImplementedError(SKIP_REASONS["shooting-iteration"])
        return
    if method == "shooting" and n >= 100:
        raise NotImplementedError(SKIP_REASONS["shooting-large"])
    if method == "penalty" and n >= 1000 and harmonics is not None and harmonics >= 9:
        raise NotImplementedError(SKIP_REASONS["penalty-1000-high"])


@functools.cache
def reference_frequency(name: str, harmonics: int = 5, amplitude_gaps: float = AMPLITUDE_GAPS) -> float:
    """Reference frequency (Hz) at ``amplitude_gaps``.

    One-DOF oscillator: the closed form. Beam: MMS-HBM at the same H with 1024 samples per
    period (converged in N). On the beam neither the exact orbit nor MMS-HBM in H converge
    at 2 gaps (multiple contacts per period, internal resonances): the tracked error of the
    beam is therefore that of the H-harmonic problem (AFT for MMS-HBM, penalty for
    penalty-HBM), see mmshbm/benchmarking.py. NaN if the reference does not reach the
    amplitude.
    """
    import mmshbm
    from mmshbm.analysis.benchmarking import _reached_frequency, load_model

    m, osc = load_model(name)
    if osc is not None:
        return float(osc.frequency(amplitude_gaps * m.gap))
    b = mmshbm.backbone(m, harmonics=harmonics, max_amplitude=amplitude_gaps * m.gap, n_samples=1024)
    return _reached_frequency(b, amplitude_gaps * m.gap)


def point_near(branch, amplitude: float) -> int:
    """Index of the branch point whose amplitude is closest to ``amplitude`` (m)."""
    return int(np.argmin(np.abs(branch.amplitude - amplitude)))
