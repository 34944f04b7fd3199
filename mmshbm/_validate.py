"""Input checks shared by the public entry points.

Every check raises ``ValueError`` or ``TypeError`` with a message that names the
offending argument and its value, so that a user never sees a NumPy traceback from
deep inside a solver.
"""

from __future__ import annotations

import math
import numbers

import numpy as np
import scipy.sparse as sp


def positive(name: str, value) -> float:
    """Return ``value`` as a float after checking that it is a finite number > 0."""
    x = real_number(name, value)
    if not x > 0.0:
        raise ValueError(f"{name} must be positive, got {value!r}")
    return x


def non_negative(name: str, value) -> float:
    """Return ``value`` as a float after checking that it is a finite number >= 0."""
    x = real_number(name, value)
    if x < 0.0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return x


def real_number(name: str, value) -> float:
    """Return ``value`` as a finite float; reject bools, strings, NaN and inf."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__} {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return x


def integer(name: str, value, minimum: int | None = None) -> int:
    """Return ``value`` as an int after checking its type and lower bound."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__} {value!r}")
    n = int(value)
    if minimum is not None and n < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {n}")
    return n


def square_matrix(name: str, A) -> sp.csr_matrix:
    """Return ``A`` (dense or sparse) as a CSR float matrix, checked square and finite."""
    if sp.issparse(A):
        A = sp.csr_matrix(A, dtype=float)
    else:
        try:
            A = np.asarray(A, dtype=float)
        except (TypeError, ValueError) as err:
            raise TypeError(f"{name} must be a 2-D array or sparse matrix of numbers: {err}") from None
        if A.ndim != 2:
            raise ValueError(f"{name} must be 2-D, got an array of shape {A.shape}")
        A = sp.csr_matrix(A)
    if A.shape[0] != A.shape[1]:
        raise ValueError(f"{name} must be square, got shape {A.shape}")
    if A.shape[0] == 0:
        raise ValueError(f"{name} is empty")
    if not np.all(np.isfinite(A.data)):
        coo = A.tocoo()
        k = int(np.flatnonzero(~np.isfinite(coo.data))[0])
        i, j = int(coo.row[k]), int(coo.col[k])
        raise ValueError(f"{name} has a non-finite entry {float(coo.data[k])} at {(i, j)}")
    A.eliminate_zeros()
    A.sort_indices()
    return A


def symmetric(name: str, A: sp.csr_matrix, rtol: float = 1e-10) -> None:
    """Raise if the sparse matrix ``A`` is not symmetric to ``rtol`` of its largest entry."""
    scale = abs(A).max() if A.nnz else 0.0
    asym = abs(A - A.T)
    worst = asym.max() if asym.nnz else 0.0
    if worst > rtol * scale:
        coo = asym.tocoo()  # sparse: a large model must not be densified to name the entry
        k = int(np.argmax(coo.data))
        i, j = int(coo.row[k]), int(coo.col[k])
        raise ValueError(
            f"{name} must be symmetric: {name}[{i},{j}] = {float(A[i, j])!r} but "
            f"{name}[{j},{i}] = {float(A[j, i])!r}"
        )
