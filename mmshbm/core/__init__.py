"""Numerical core: harmonic transforms, condensation of the linear structure, Numba
kernels, path following, checkpoints, the per-point measures (:mod:`.measures`). Imports
:mod:`mmshbm.model` below it and the contact laws beside it (:mod:`mmshbm.contact`)."""
