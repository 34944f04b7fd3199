"""Numerical core: path following (predictor, corrector, step control), bordered solves,
events, statuses, checkpoints and the per-point measures (:mod:`.measures`). Knows no
method: the condensation and transforms are :mod:`mmshbm.harmonic`, MMS-HBM's kernels
:mod:`mmshbm.methods.mms`. Imports :mod:`mmshbm.model` and :mod:`mmshbm.harmonic` below it
and the contact laws beside it (:mod:`mmshbm.contact`)."""
