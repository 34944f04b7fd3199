"""The harmonic-balance toolkit the methods share, beneath the continuation core: the
time-frequency transform (:mod:`.harmonics`: AFT sampling, pyfftw plans), the linear
structure's dynamic stiffness per harmonic condensed onto a set of DOFs
(:mod:`.condense`: banded/sparse LU; :mod:`.modal` with :mod:`.modal_reduction`: modal
back end for large models), the modal kinetic-energy shares (:mod:`.modal_energy`) and the
banded and dense linear-algebra kernels (:mod:`.kernels`). Knows no method and no
continuation: imports only :mod:`mmshbm.model` below it."""
