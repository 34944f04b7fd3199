"""A string of masses hanging on massless contact nodes: the scaling model for many contacts.

``n`` masses ``m`` in a line, joined to each other and to two fixed walls by springs
``k_string`` (a taut string's lumped model); each mass hangs on its own massless node by a
spring ``k_contact``, and each node faces a rigid stop ``gap`` away on its + side. DOFs:
``q = [x_mass_0 .. x_mass_{n-1}, x_node_0 .. x_node_{n-1}]``. The condensed dynamic
stiffness D_k couples every pair of contacts (through the string), so the contact
subsystem is dense: n contact DOFs, n_c = n. The branch's amplitude is the middle mass's.

With every contact open the nodes follow their masses, and the linear modes are those of
the string: ω_j = 2 √(k_string/m) sin(jπ / (2(n+1))).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .. import _validate as check
from ..model.model import Model

__all__ = ["contact_string"]


def contact_string(n: int, *, m: float = 1.0, k_string: float = 1.0, k_contact: float = 4.0,
                   gap: float = 1.0) -> Model:
    """The string of ``n`` masses on ``n`` massless contact nodes (module docstring).

    Parameters
    ----------
    n : int
        Masses, and contact nodes (>= 1).
    m : float
        Each mass (kg).
    k_string : float
        Each spring of the string, the two to the walls included (N/m).
    k_contact : float
        Each spring from a mass to its contact node (N/m).
    gap : float
        Distance (m) from each node's rest position to its stop (+ side).
    """
    n = check.integer("n", n, minimum=1)
    for name, value in (("m", m), ("k_string", k_string), ("k_contact", k_contact)):
        check.positive(name, value)
    check.non_negative("gap", gap)
    main = np.full(n, 2 * k_string + k_contact)
    off = np.full(n - 1, -k_string)
    K_ll = sp.diags([off, main, off], [-1, 0, 1])
    K_lc = -k_contact * sp.identity(n)
    K = sp.bmat([[K_ll, K_lc], [K_lc, k_contact * sp.identity(n)]], format="csr")
    M = sp.block_diag([m * sp.identity(n), sp.csr_matrix((n, n))], format="csr")
    return Model.from_matrices(M, K, contact_dof=list(range(n, 2 * n)), gap=gap, stop_side=1,
                               amplitude_dof=n // 2,
                               description={"kind": "contact_string", "n": n, "m": m, "k_string": k_string,
                                            "k_contact": k_contact, "gap": gap})
