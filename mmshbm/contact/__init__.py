"""Contact laws at DOFs, as proximal point equations with their pointwise kernels and exact
harmonic projections, and the pieces the laws share.

Laws (one module each):

* :mod:`mmshbm.contact.unilateral`: the unilateral (Signorini) law of a rigid stop, or of
  two (a clearance, the same law with both bounds finite): the proximal map
  (:func:`proximal_contact`) and its harmonic projection on an admissible interval
  (:func:`project_contact`).
* :mod:`mmshbm.contact.coulomb`: Coulomb dry friction with slip force s = μN,
  f = clip(f + r u̇, −s, s): pointwise kernels, the exact projection of this velocity-level
  form (through the unilateral projection on [−s, s]) and of its time integral (the play
  operator, displacement level); :mod:`mmshbm.contact.coulomb_coupled` couples the slip
  force to a varying normal load.

Shared pieces:

* :mod:`mmshbm.contact.trig`: trigonometric polynomials and their zeros (the switching
  instants of a law on a harmonic-balance point), located to round-off.
* :mod:`mmshbm.contact.projection`: the spectrum of an active set (sampled or exact) and
  the product matrices that turn it into a projection and its Jacobian.
* :mod:`mmshbm.contact.lcp`: the static contact problem of several stops at one instant
  (an LCP), solved exactly by principal pivoting.
* :mod:`mmshbm.contact.static`: the massless DOFs and contact forces that follow
  statically from the DOFs with mass (admissible signals of a harmonic-balance point).
* :mod:`mmshbm.contact.table`: a model's contacts as arrays, the static stiffness at each,
  penalty values, the contacts in terms of the DOFs with mass, the start mode.

The package sits at the layer of the numerical core (:mod:`mmshbm.core`): the core's
fused MMS-HBM residuals (:mod:`mmshbm.methods.mms.contact_kernels`) call its kernels; it uses the
core's condensation for the static stiffness. Kernels take their flags and cache policy
from :mod:`mmshbm._kernel_cache`. docs/design.md says how to add a law.
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
from .unilateral import project_contact, proximal_contact

__all__ = ["proximal_contact", "project_contact", "coulomb_residual", "coulomb_derivative", "project_coulomb",
           "project_coulomb_play", "play_pieces", "derivative_matrix"]
