"""Compiled overloads of the package's kernels, resolved once per argument types.

Numba's dispatcher works out the type of every argument on each call; named tuples of
arrays take its slow path (≈ 1 µs a tuple), and typing the compiled corrector's full
argument tuple from scratch (:func:`~mmshbm.methods.mms.corrector_kernels.newton_modal_entry`)
costs ≈ 1 ms, once per problem, so once per backbone. :func:`compiled_entry` keys the
overload on a cheap description of what Numba's ``typeof`` reads from each argument (an
array's dtype, ndim, layout, writeability and alignment; the class of a scalar, an int's
range; a tuple's class and fields) and keeps the entry point per kernel and key: a later
problem whose arguments have the same types gets it from a dictionary. Problems whose
arguments agree in type by construction share their entry points without describing
the arguments at all (``kept``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["compiled_entry"]

#: (kernel, type key) -> compiled entry point
_ENTRIES: dict = {}
_INT64 = (-(2**63), 2**63)
#: the array flags Numba's type depends on: C_CONTIGUOUS, F_CONTIGUOUS, ALIGNED, WRITEABLE
_FLAGS = 0x1 | 0x2 | 0x100 | 0x400


def _type_key(value):
    """What Numba's ``typeof`` of ``value`` depends on, as a hashable tuple; None for a
    value this function does not describe (the caller then types it in full)."""
    cls = type(value)
    if cls is np.ndarray:
        return (value.dtype, value.ndim, value.flags.num & _FLAGS)
    if isinstance(value, np.ndarray):
        return (cls, value.dtype, value.ndim, value.flags.num & _FLAGS)
    if cls is float or cls is bool:
        return cls
    if cls is int:
        return (int, _INT64[0] <= value < _INT64[1])
    if isinstance(value, tuple):
        keys = tuple(_type_key(v) for v in value)
        return None if None in keys else (cls, keys)
    if isinstance(value, np.generic):
        return cls
    return None


def compiled_entry(dispatcher, args: tuple, kept: dict | None = None):
    """The compiled overload of ``dispatcher`` (a Numba dispatcher) for the types of
    ``args`` (its full argument tuple), as a plain callable: compiled, or taken from the
    disk cache, on first use; later calls with arguments of the same types get the same
    entry point without typing them again. Every call of the entry point must pass
    arguments of the types it was resolved for.

    ``kept`` (dispatcher -> entry point) is shared by callers whose arguments are made by
    the same code from copies of the same arrays, so that their types agree by
    construction (the MMS-HBM problems built from one set of kept numbers,
    :mod:`mmshbm.methods.mms.fixed`): an entry found there is returned without describing
    the arguments, and one resolved here is put there."""
    if kept is not None:
        entry = kept.get(dispatcher)
        if entry is not None:
            return entry
    key = _type_key(args)
    entry = _ENTRIES.get((dispatcher, key)) if key is not None else None
    if entry is None:
        entry = dispatcher.compile(tuple(dispatcher.typeof_pyval(a) for a in args))
        if key is not None:
            _ENTRIES[dispatcher, key] = entry
    if kept is not None:
        kept[dispatcher] = entry
    return entry
