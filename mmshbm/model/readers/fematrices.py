"""The matrices of an FE export, with its DOF table, and the :class:`~mmshbm.model.Model`
built from them with contacts and friction named by node and component.

A DOF named for a contact or for friction must be massless for MMS-HBM (its equation is
static). Exports carry mass on every node, so :meth:`FEMatrices.model` joins a new massless
node to each named DOF that carries mass by a spring of stiffness ``k`` (N/m), the *layer*
of :func:`mmshbm.model.transforms.with_contact_layer`: the structure is unchanged while the
contact is open, and ``1/k`` is the compliance of the contact. Default ``k``:
``DEFAULT_LAYER_FACTOR`` (10⁵) times the static stiffness of the structure at that DOF,
k_s = (e_tᵀ K⁻¹ e_t)⁻¹, which puts the backbone within ~1e-5 of a rigid stop on the DOF
with mass (docs/fe_models.md); for friction the layer is the tangential contact stiffness
(a Jenkins element), physical: give a measured one when there is one.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["FEMatrices", "id_ranges"]

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class FEMatrices:
    """Mass, stiffness and (optionally) damping of an FE export, constrained DOFs removed.

    Attributes
    ----------
    M, K : scipy.sparse.csr_matrix, shape (n, n)
        Symmetric mass (kg, kg·m²) and stiffness (N/m, N·m/rad) in the units of the export
        (mmshbm assumes SI: check :meth:`frequencies`).
    C : scipy.sparse.csr_matrix or None, shape (n, n)
        Viscous damping (N·s/m) where the export has one.
    dofs : ndarray of int, shape (n, 2)
        Node id and component of each row (components 1..6: ux, uy, uz, rx, ry, rz as the
        packages number them; 0 where the format names no DOFs: the node is then the row
        index, 0-based).
    source : tuple of str
        The files read.
    format : str
        The format they were read as (e.g. ``"abaqus"``, ``"op4"``).
    removed : ndarray of int, shape (r, 2)
        (node, component) of the DOFs removed as constrained (zero rows, Lagrange
        multipliers and the DOFs they fix).
    """

    M: sp.csr_matrix
    K: sp.csr_matrix
    C: sp.csr_matrix | None
    dofs: np.ndarray
    source: tuple = ()
    format: str = ""
    removed: np.ndarray | None = None

    @property
    def n_dof(self) -> int:
        """Number of DOFs (rows of M and K)."""
        return self.K.shape[0]

    @property
    def nodes(self) -> np.ndarray:
        """The node ids of the DOF table, ascending, shape (n_nodes,)."""
        return np.unique(self.dofs[:, 0])

    @cached_property
    def _lookup(self) -> dict:
        return {(int(a), int(b)): i for i, (a, b) in enumerate(self.dofs)}

    def index(self, node: int, component: int) -> int:
        """The row of DOF (``node``, ``component``); ValueError naming what the table holds."""
        key = (int(node), int(component))
        if key in self._lookup:
            return self._lookup[key]
        if key[0] in set(self.dofs[:, 0].tolist()):
            have = sorted(int(c) for c in self.dofs[self.dofs[:, 0] == key[0], 1])
            raise ValueError(f"node {key[0]} has no component {key[1]} (it has {have})"
                             + self._removed_note(key))
        plain = bool(np.all(self.dofs[:, 1] == 0))
        what = (f"the DOFs are plain indices 0..{self.n_dof - 1} (component 0)" if plain else
                f"nodes {id_ranges(self.nodes)}")
        raise ValueError(f"no DOF (node {key[0]}, component {key[1]}) in "
                         f"{', '.join(self.source) or 'the model'}:"
                         f" {what}" + self._removed_note(key))

    def _removed_note(self, key) -> str:
        if self.removed is not None and len(self.removed) and \
                np.any((self.removed[:, 0] == key[0]) & (self.removed[:, 1] == key[1])):
            return " (it was removed as constrained)"
        return ""

    @cached_property
    def open_model(self):
        """The structure as a :class:`~mmshbm.model.Model` without contacts (for modes)."""
        from ..model import Model

        return Model.from_matrices(self.M, self.K, [], [], [], {"kind": "FEMatrices",
                                                                 "source": list(self.source)})

    def frequencies(self, n: int = 6) -> np.ndarray:
        """The ``n`` lowest natural frequencies (Hz) of the free structure (no contact), shape
        (n,). A first frequency far from what you expect is the quickest check of units
        (mm with tonnes gives Hz as SI does; mm with kg does not)."""
        return self.open_model.linear_frequencies(n)

    def static_stiffness(self, rows) -> np.ndarray:
        """Static stiffness (N/m) of the structure at each of ``rows``, (e_tᵀ K⁻¹ e_t)⁻¹,
        by one sparse factorisation (minimum-degree order), shape (len(rows),)."""
        rows = np.asarray(rows, dtype=np.int64)
        lu = spla.splu(sp.csc_matrix(self.K), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
        E = np.zeros((self.n_dof, len(rows)))
        E[rows, np.arange(len(rows))] = 1.0
        return 1.0 / lu.solve(E)[rows, np.arange(len(rows))]

    def model(self, contact=(), friction=(), layer_stiffness=None, *, damping: bool = True,
              amplitude=None):
        """A :class:`~mmshbm.model.Model` of the structure with rigid stops and friction
        named by node and component.

        Parameters
        ----------
        contact : sequence of (node, component, gap, side)
            One rigid stop each: ``gap`` (m) > 0, ``side`` +1 (stop at q = +gap, default
            when a 3-tuple) or -1.
        friction : sequence of (node, component, mu, normal_load)
            Coulomb friction, coefficient ``mu`` >= 0, constant normal force (N) >= 0.
        layer_stiffness : float or dict, optional
            Stiffness (N/m) of the massless layer joined to every named DOF that carries
            mass; a dict maps (node, component) to its own stiffness. Default: 10⁵ times
            the static stiffness at that DOF (see the module notes). The values used are in
            ``model.description["contact_layer"]`` and logged.
        damping : bool
            Keep the export's damping matrix C (if any).
        amplitude : (node, component), optional
            The DOF whose excursion is the amplitude (default: the first contact's DOF, or
            the first friction DOF).

        Raises
        ------
        ValueError, TypeError
            A node or component the DOF table does not hold, a malformed entry (named by
            its position), a DOF named twice for friction, and the errors of
            :meth:`Model.from_matrices`.
        """
        from ..model import Model

        stops = [_contact_entry(e, i) for i, e in enumerate(contact)]
        slips = [_friction_entry(e, i) for i, e in enumerate(friction)]
        if not stops and not slips:
            raise ValueError("give at least one contact=(node, component, gap, side) or friction=(node, "
                             "component, mu, normal_load): the model needs a nonlinearity")
        named = [self.index(node, comp) for node, comp, *_ in stops + slips]
        mass_rows = np.asarray(abs(self.M).sum(axis=1)).ravel() > 0
        carry = sorted({r for r in named if mass_rows[r]})
        K, M, C = self.K, self.M, (self.C if damping else None)
        where = {r: r for r in named}
        layer = {}
        if carry:
            ks = self.static_stiffness(carry)  # one factorisation of K for every layer
            k = self._layer_stiffness(carry, layer_stiffness, ks)
            K, M, C, new = _add_layer(K, M, C, carry, k)
            where.update(dict(zip(carry, new.tolist(), strict=True)))
            layer = {"attached_to": [self._name(r) for r in carry], "nodes": new.tolist(),
                     "stiffness": k.tolist(), "static_stiffness": ks.tolist(),
                     "ratio_to_static": (k / ks).tolist()}
            log.info("massless layer on %s: k = %s N/m", layer["attached_to"],
                     ", ".join(f"{v:.4g}" for v in k))
        dofs = [where[r] for r in named[:len(stops)]]
        amp_row = self.index(*amplitude) if amplitude is not None else named[0]
        description = {"kind": "FEMatrices", "source": list(self.source), "format": self.format,
                       "contacts_named": [list(map(_plain, s)) for s in stops],
                       "friction_named": [list(map(_plain, s)) for s in slips]}
        if layer:
            description["contact_layer"] = layer
        model = Model.from_matrices(M, K, dofs, [s[2] for s in stops], [s[3] for s in stops], description,
                                    damping=C, amplitude_dof=amp_row)
        for (_, _, mu, load), r in zip(slips, named[len(stops):], strict=True):
            model = model.with_friction(where[r], mu, normal_load=load)
        return model

    def _layer_stiffness(self, rows, given, static: np.ndarray) -> np.ndarray:
        from ..transforms import DEFAULT_LAYER_FACTOR

        if given is None:
            return DEFAULT_LAYER_FACTOR * static
        out = []
        for r, k_s in zip(rows, static, strict=True):
            value = given.get(tuple(int(v) for v in self.dofs[r])) if isinstance(given, dict) else given
            if value is None:
                value = DEFAULT_LAYER_FACTOR * float(k_s)
            if isinstance(value, bool) or not isinstance(value, int | float | np.number) or \
                    not np.isfinite(value) or value <= 0:
                raise ValueError(f"layer_stiffness for {self._name(r)} must be a finite stiffness > 0 (N/m), "
                                 f"got {value!r}")
            out.append(float(value))
        return np.array(out)

    def _name(self, row: int) -> list:
        return [int(self.dofs[row, 0]), int(self.dofs[row, 1])]

    def __repr__(self) -> str:
        return (f"FEMatrices(n_dof={self.n_dof}, nodes={id_ranges(self.nodes)}, format={self.format!r}, "
                f"damping={'yes' if self.C is not None else 'no'}, "
                f"removed={0 if self.removed is None else len(self.removed)})")


def _add_layer(K, M, C, rows, k):
    """K, M, C with a massless node per row joined to it by a spring k (N/m); the new nodes'
    rows follow the old ones."""
    n, m = K.shape[0], len(rows)
    t = np.asarray(rows)
    new = n + np.arange(m)
    spring = sp.csr_matrix((np.concatenate([k, -k, -k, k]),
                            (np.concatenate([t, t, new, new]), np.concatenate([t, new, t, new]))),
                           shape=(n + m, n + m))
    pad = sp.csr_matrix((m, m))
    K2 = (sp.block_diag([K, pad], format="csr") + spring).tocsr()
    M2 = sp.block_diag([M, pad], format="csr")
    C2 = None if C is None else sp.block_diag([C, pad], format="csr")
    return K2, M2, C2, new


def _plain(v):
    return v.item() if isinstance(v, np.generic) else v


def _number(value, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.number):
        raise TypeError(f"{what} must be a number, got {type(value).__name__} {value!r}")
    return float(value)


def _contact_entry(entry, i: int) -> tuple:
    try:
        items = list(entry)
    except TypeError:
        raise TypeError(f"contact[{i}] must be (node, component, gap[, side]), got {entry!r}") from None
    if len(items) not in (3, 4):
        raise ValueError(f"contact[{i}] must be (node, component, gap[, side]), got {entry!r}")
    node, comp, gap = int(items[0]), int(items[1]), _number(items[2], f"contact[{i}] gap")
    side = int(items[3]) if len(items) == 4 else 1
    if not gap >= 0 or not np.isfinite(gap):
        raise ValueError(f"contact[{i}] gap must be >= 0 (m), got {items[2]!r}")
    if side not in (1, -1):
        raise ValueError(f"contact[{i}] side must be +1 or -1, got {items[3]!r}")
    return node, comp, gap, side


def _friction_entry(entry, i: int) -> tuple:
    try:
        items = list(entry)
    except TypeError:
        raise TypeError(f"friction[{i}] must be (node, component, mu, normal_load), got {entry!r}") from None
    if len(items) != 4:
        raise ValueError(f"friction[{i}] must be (node, component, mu, normal_load), got {entry!r}")
    return (int(items[0]), int(items[1]), _number(items[2], f"friction[{i}] mu"),
            _number(items[3], f"friction[{i}] normal_load"))


def id_ranges(values) -> str:
    """``[1, 2, 3, 7, 9, 10]`` -> ``"1-3, 7, 9-10"``."""
    values = sorted(int(v) for v in values)
    out, start = [], None
    for a, b in zip(values, values[1:] + [None], strict=True):
        start = a if start is None else start
        if b != a + 1:
            out.append(f"{start}" if start == a else f"{start}-{a}")
            start = None
    return ", ".join(out)
