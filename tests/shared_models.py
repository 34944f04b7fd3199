"""Models that several test modules share; tests/conftest.py makes fixtures of them."""

import mmshbm
from mmshbm.fe.euler_bernoulli import cantilever_model

#: NLvib's cantilever with an impact at its tip: length, width, height (m), Young's modulus
#: (Pa), density (kg/m³), gap (m)
L, B, H_SEC, E, RHO, GAP = 0.5, 0.020, 0.0135, 210e9, 7850.0, 1e-3


def nlvib_cantilever(n_elements: int = 21) -> mmshbm.Model:
    """NLvib's Euler–Bernoulli cantilever with a full mass matrix (the contact DOF has mass)."""
    return cantilever_model(L, B, H_SEC, E, RHO, n_elements, GAP)


def default_beam(n_elements: int) -> mmshbm.Model:
    """The default beam (mmshbm.default_beam) meshed with ``n_elements`` elements."""
    return mmshbm.default_beam().model(n_elements)
