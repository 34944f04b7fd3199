"""The harmonic projection of the contact law, at the path of earlier releases: the
projection lives in :mod:`mmshbm.contact.unilateral` (the law) and
:mod:`mmshbm.contact.projection` (the spectrum and product matrices shared by the laws),
the damped MMS-HBM contact rows in :mod:`mmshbm.core.contact_kernels`. Every name here is
the object of its new home."""

from __future__ import annotations

from ..contact.projection import (  # noqa: F401
    _add_product_matrix,
    _check_samples,
    _product_matrix,
    contact_spectrum,
    sample_tables,
)
from ..contact.unilateral import _project, project_contact  # noqa: F401
from .contact_kernels import _block_times, _contact_rows, _damped_residual  # noqa: F401

__all__ = ["project_contact", "contact_spectrum", "sample_tables"]
