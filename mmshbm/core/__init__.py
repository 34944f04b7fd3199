"""Numerical core: harmonic transforms, condensation of the linear structure, Numba
kernels, path following, checkpoints. Imports only :mod:`mmshbm.model` below it."""
