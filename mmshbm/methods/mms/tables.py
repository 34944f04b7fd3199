"""The sample grids of an MMS-HBM problem and their cosine and sine tables, kept per
(H, N)."""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["_tables", "_tables_kept"]


def _tables(H: int, N: int) -> tuple[np.ndarray, ...]:
    """(τ (N,), cos kτ (2H+1, N), sin kτ (H+1, N), fine τ (n_fine,), cos kτ (H+1, n_fine) on
    it) of an MMS-HBM problem, n_fine = max(512, 8N); kept per (H, N) up to
    :data:`_TABLES_KEPT` numbers (read only: a problem takes copies)."""
    if _tables_kept(H, N):
        return _kept_tables(H, N)
    return _compute_tables(H, N)


def _tables_kept(H: int, N: int) -> bool:
    """Whether :func:`_tables` keeps the tables of (H, N) (else it computes them at each call)."""
    return (3 * H + 2) * N + (H + 2) * max(512, 8 * N) <= _TABLES_KEPT


#: the largest tables (numbers) :func:`_tables` keeps (8 MB)
_TABLES_KEPT = 1 << 20


@functools.lru_cache(maxsize=32)
def _kept_tables(H: int, N: int) -> tuple[np.ndarray, ...]:
    return _compute_tables(H, N)


def _compute_tables(H: int, N: int) -> tuple[np.ndarray, ...]:
    tau = 2 * np.pi * np.arange(N) / N
    n_fine = max(512, 8 * N)
    tau_fine = 2 * np.pi * np.arange(n_fine) / n_fine
    return (tau, np.cos(np.outer(np.arange(2 * H + 1), tau)), np.sin(np.outer(np.arange(H + 1), tau)),
            tau_fine, np.cos(np.outer(np.arange(H + 1), tau_fine)))
