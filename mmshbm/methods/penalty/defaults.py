"""Defaults of penalty harmonic balance: the samples per period for a given penalty
stiffness, and the contact stiffness k_c that the penalty stiffness is a multiple of."""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...contact.table import DEFAULT_PENALTY_FACTOR, static_contact_stiffness
from ...harmonic.harmonics import check_harmonics, default_n_samples
from ...model.model import Model

__all__ = ["DEFAULT_PENALTY_FACTOR", "penalty_n_samples"]


def penalty_n_samples(harmonics: int, penalty_factor: float) -> int:
    """Default samples per period N for penalty HBM with k_p = ``penalty_factor`` · k_c.

    ``default_n_samples(H)`` for k_p <= 10³ k_c, times 2 per further decade (rounded up).
    In the k_p -> oo limit the penalty force concentrates into ever shorter pulses at the
    instants the contact displacement touches the stop; unresolved by the samples, the
    sampled residual jumps as single samples switch and the continuation stalls (on the
    default beam at H = 10 and 20, k_p = 10⁴ k_c stopped at 1.1 gaps with the default N
    and runs to 10 gaps with 2× N; docs/penalty.md).
    """
    H = check_harmonics(harmonics)[0]
    factor = check.positive("penalty_factor", penalty_factor)
    doublings = max(0, int(np.ceil(np.log10(factor / DEFAULT_PENALTY_FACTOR) - 1e-9)))
    return default_n_samples(H) * 2**doublings


def _condensed_contact_stiffness(model: Model) -> float:
    """k_c (N/m): the static stiffness of the structure at the contact of a single-contact
    model (with several contacts, the smallest over the contacts); see
    :func:`~mmshbm.contact.table.static_contact_stiffness`."""
    return float(static_contact_stiffness(model).min())
