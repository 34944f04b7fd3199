"""Resource estimates checked before a solver allocates anything.

:func:`check_resources` estimates the memory a method needs for a model, H, N (or
shooting's steps per period) and raises a ``ValueError`` that names the setting, the
estimate and the largest H that fits, when the estimate exceeds :func:`memory_limit`
(the memory this machine has available, or ``MMSHBM_MEMORY_LIMIT`` in bytes). An
estimate above :data:`LARGE_RUN_BYTES` is logged as a warning (such runs take minutes).

The estimates count the arrays that grow with the setting, with a factor 2 for the
temporaries that build them:

- MMS-HBM: the fine cosine grid of the monitor, (H+1)·max(512, 8N) doubles; the dense
  Newton matrix ((H+1)·n_c)²; the condensed stiffness and its derivative, 2(H+1)·n_c²;
  the band storage of the condensation, n_l·(3b+1) (b the half bandwidth, bounded by
  n_l).
- penalty-HBM: the same fine grid; the sparse Jacobian, (H+1)·nnz(K) + ((H+1))² for
  the contact rows, times 10 for the LU's fill-in.
- shooting: the orbit (positions, velocities) at N steps, 2N·n_l; the sensitivities
  and the Newton matrix, 3·n_l².

They are estimates (the real peak is within a factor two of them on the default beam);
they exist to refuse in a second what would fail after minutes, e.g. ``-H 5000`` (an
80 GB cosine table), not to budget memory to the byte.
"""

from __future__ import annotations

import logging
import os

__all__ = ["estimate_memory", "check_resources", "check_beam_elements", "memory_limit", "LARGE_RUN_BYTES"]

log = logging.getLogger(__name__)

#: estimates above this (bytes) are logged as a warning: expect a long run
LARGE_RUN_BYTES = 1 << 30
_DOUBLE = 8
#: estimates up to this (bytes) are not compared with the memory the system reports (reading
#: it costs more than such a run's setup); ``MMSHBM_MEMORY_LIMIT`` applies to every run
_SMALL_RUN_BYTES = 64 << 20


def memory_limit() -> int:
    """Bytes a run may use: ``MMSHBM_MEMORY_LIMIT`` if set, else the memory the system
    reports available (``MemAvailable``), else half the physical memory, else 8 GiB."""
    env = os.environ.get("MMSHBM_MEMORY_LIMIT")
    if env:
        try:
            value = int(float(env))
        except ValueError:
            raise ValueError(f"MMSHBM_MEMORY_LIMIT must be a number of bytes, got {env!r}") from None
        if value <= 0:
            raise ValueError(f"MMSHBM_MEMORY_LIMIT must be positive, got {env!r}")
        return value
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")) // 2
    except (ValueError, OSError, AttributeError):
        return 8 << 30


def _sizes(model) -> tuple[int, int, int]:
    n = int(model.n_dof)
    n_c = len(model.c)
    n_l = n - n_c
    return n, n_c, n_l


def estimate_memory(model, method: str, harmonics: int = 5, n_samples: int | None = None,
                    steps_per_period: int | None = None, penalty_factor: float | None = None) -> int:
    """Estimated peak memory (bytes) of a backbone of ``method`` on ``model``.

    Parameters
    ----------
    model : Model
    method : {"mmshbm", "penalty", "shooting"}
    harmonics : int
        H (harmonic-balance methods).
    n_samples : int, optional
        N (default the method's).
    steps_per_period : int, optional
        Shooting's steps (default the method's).
    penalty_factor : float, optional
        k_p / k_c of penalty-HBM (for its default N).
    """
    from .._method_info import method_info

    memory = method_info(method).memory_model
    n, n_c, n_l = _sizes(model)
    if memory == "time-march":
        from .shooting.conservative import DEFAULT_STEPS_PER_PERIOD

        N = int(steps_per_period or DEFAULT_STEPS_PER_PERIOD)
        return _DOUBLE * (2 * N * n_l + 3 * n_l * n_l)
    from ..harmonic.harmonics import default_n_samples

    H = int(harmonics)
    if n_samples is None:
        if memory == "assembled":
            from .penalty.defaults import DEFAULT_PENALTY_FACTOR, penalty_n_samples

            n_samples = penalty_n_samples(H, penalty_factor or DEFAULT_PENALTY_FACTOR)
        else:
            n_samples = default_n_samples(H)
    n_fine = max(512, 8 * int(n_samples))
    grid = 2 * (H + 1) * n_fine
    if memory == "assembled":
        nnz = int(model.K.nnz)
        return _DOUBLE * (grid + 10 * ((H + 1) * nnz + (H + 1) ** 2))
    band = min(n_l, max(8, int(n_l**0.5)))
    return _DOUBLE * (grid + ((H + 1) * n_c) ** 2 + 2 * (H + 1) * n_c * n_c + n_l * (3 * band + 1))


def check_resources(model, method: str, options: dict) -> int:
    """Raise ``ValueError`` when a run would not fit in :func:`memory_limit` (a run
    estimated at most ``_SMALL_RUN_BYTES`` fits, unless ``MMSHBM_MEMORY_LIMIT`` is set).

    ``options`` are the method options of :func:`mmshbm.backbone` (``harmonics``,
    ``n_samples``, ``steps_per_period``, ``penalty_stiffness``). Returns the estimate
    (bytes).
    """
    H = options.get("harmonics", 5)
    est = estimate_memory(model, method, H, options.get("n_samples"), options.get("steps_per_period"))
    if est <= _SMALL_RUN_BYTES and not os.environ.get("MMSHBM_MEMORY_LIMIT"):
        return est
    limit = memory_limit()
    from .._method_info import is_harmonic_balance

    what = (f"steps_per_period = {options.get('steps_per_period')}" if not is_harmonic_balance(method)
            else f"harmonics = {H}" + (f", n_samples = {options['n_samples']}"
                                       if options.get("n_samples") else ""))
    if est > limit:
        hint = ""
        if is_harmonic_balance(method):
            fits = [h for h in (2000, 1000, 500, 200, 100, 50, 20, 10, 5, 1)
                    if estimate_memory(model, method, h) <= limit]
            hint = f"; about H = {fits[0]} fits" if fits else ""
        raise ValueError(f"{method} with {what} on {model.n_dof} DOFs needs about {_gb(est)} of memory "
                         f"(estimate), more than the {_gb(limit)} available{hint} (MMSHBM_MEMORY_LIMIT "
                         "sets the limit in bytes)")
    if est > LARGE_RUN_BYTES:
        log.warning("%s with %s on %d DOFs needs about %s of memory (estimate): expect a run of minutes",
                    method, what, model.n_dof, _gb(est))
    return est


#: bytes per beam element while a model is assembled (COO triplets of M and K, their CSR
#: copies, the partitioned blocks and the band storage of the condensation)
BEAM_BYTES_PER_ELEMENT = 4096
#: seconds per element of a default backbone (H = 5, 10 gaps), measured on 1000 elements
#: (about 2 s on this project's 2-core machine): a rough time estimate, not a promise
BEAM_SECONDS_PER_ELEMENT = 2e-3


def check_beam_elements(n_elements: int) -> int:
    """Refuse (``ValueError``) a beam mesh whose assembly alone would not fit in
    :func:`memory_limit`, and log a warning with a rough time estimate for meshes whose
    backbone takes minutes; returns the memory estimate (bytes)."""
    est = int(n_elements) * BEAM_BYTES_PER_ELEMENT
    limit = memory_limit()
    if est > limit:
        raise ValueError(f"a beam of {n_elements} elements needs about {_gb(est)} of memory to assemble "
                         f"(estimate), more than the {_gb(limit)} available")
    seconds = n_elements * BEAM_SECONDS_PER_ELEMENT
    if seconds > 60:
        log.warning("a beam of %d elements: expect about %.0f minutes per backbone (estimate)", n_elements,
                    seconds / 60)
    return est


def _gb(x: float) -> str:
    return f"{x / 2**30:.3g} GiB" if x >= 2**27 else f"{x / 2**20:.3g} MiB"
