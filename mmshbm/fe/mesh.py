"""One-dimensional meshes of a beam: geometrically graded element lengths and node coordinates.

The beam runs from the root (x = 0, clamped) to the tip (x = length, contact). A graded
mesh refines toward the tip so that dropping the tip node's mass changes the structure
little (Schreyer, Peter & Leine 2018, Part I, Figure 1).
"""

from __future__ import annotations

import numpy as np

from .. import _validate as check

__all__ = ["graded_lengths", "node_coordinates"]


def graded_lengths(length: float, n_elements: int, grading: float = 1.0) -> np.ndarray:
    """Element lengths in geometric progression from root to tip.

    Parameters
    ----------
    length : float
        Beam length (m), > 0.
    n_elements : int
        Number of elements, >= 1.
    grading : float
        Ratio of the first (root) to the last (tip) element length, > 0. 1.0 gives a
        uniform mesh, > 1 refines toward the tip. Ignored for one element.

    Returns
    -------
    ndarray, shape (n_elements,)
        Element lengths (m), root first; they sum to ``length``.
    """
    length = check.positive("length", length)
    n = check.integer("n_elements", n_elements, minimum=1)
    grading = check.positive("grading", grading)
    if n == 1:
        return np.array([length])
    ratio = grading ** (-1.0 / (n - 1))  # l_{i+1} / l_i
    h = ratio ** np.arange(n)
    h *= length / h.sum()
    return h


def node_coordinates(lengths) -> np.ndarray:
    """Node positions (m) from element lengths: shape (n_e + 1,), starting at 0."""
    lengths = np.atleast_1d(np.asarray(lengths, dtype=float))
    bad = np.flatnonzero(~(np.isfinite(lengths) & (lengths > 0)))
    if lengths.ndim != 1 or bad.size:
        where = (f"lengths[{bad[0]}] = {float(lengths.ravel()[bad[0]])!r}" if bad.size
                 else f"shape {lengths.shape}")
        raise ValueError(f"element lengths must be a 1-D array of finite values > 0 (m), got {where}")
    return np.concatenate([[0.0], np.cumsum(lengths)])
