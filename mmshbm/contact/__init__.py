"""Set-valued contact laws at massless DOFs, as proximal point equations with their
pointwise kernels and exact harmonic projections.

* :mod:`mmshbm.contact.coulomb`: Coulomb dry friction with slip force s = μN,
  f = clip(f + r u̇, −s, s): pointwise Numba kernels, the exact projection of this
  velocity-level form, and of its time integral (the play operator, displacement level).

The unilateral (Signorini) law lives with the numerical core
(:mod:`mmshbm.core.contact_kernels`, :mod:`mmshbm.core.projection`); this package sits at the
same layer and builds on it.
"""

from __future__ import annotations

from .coulomb import (
                      coulomb_derivative,
                      coulomb_residual,
                      derivative_matrix,
                      play_pieces,
                      project_coulomb,
                      project_coulomb_play,
)

__all__ = ["coulomb_residual", "coulomb_derivative", "project_coulomb", "project_coulomb_play", "play_pieces",
           "derivative_matrix"]
