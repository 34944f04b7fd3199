"""The structure: sparse mass and stiffness, massless contact DOFs, rigid stops.

A :class:`Model` holds a linear finite-element structure and its contacts

    M q'' + C q' + K q = Σ_i w_i λ_i,    g_i = gap_i - side_i q[dof_i],    0 <= g_i ⊥ λ_i >= 0,

with one or several rigid stops (:class:`~mmshbm.model.contact.Contact`). The DOFs whose
mass rows are zero are the *massless* DOFs ``c`` (for the beam: tip deflection and tip
rotation); the others are the *linear* DOFs ``l``. Because ``M_cc = 0`` and ``M_lc = 0``
the massless DOFs follow the others statically, which is what MMS-HBM exploits; it
needs every contact DOF among them. Models exported by FE packages carry mass on the
contact DOF: they are accepted (penalty-HBM runs them as they are), and
:meth:`Model.with_contact_layer` or :meth:`Model.with_massless_contact` turn them into
models MMS-HBM can run.

Sign convention: a contact with ``side = +1`` puts its stop at ``q[dof] = +gap``, so
``g = gap - q[dof]`` and ``w = -e_dof``; ``side = -1`` mirrors it. λ >= 0 is the contact
force's magnitude (N), pushing the structure away from the stop. The damping ``C``
(optional, N·s/m) acts on the DOFs with mass only: massless DOFs stay static.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from .. import _validate as check
from .contact import contacts_from
from .friction import no_contacts
from .linear_modes import ModesMixin
from .partition import PartitionMixin
from .stops import StopsMixin

__all__ = ["Model", "check_not_swapped"]


def check_not_swapped(M: sp.spmatrix, K: sp.spmatrix) -> None:
    """ValueError when ``K`` has zero rows where ``M`` has not: DOFs with mass and no
    stiffness at all, which no fixed structure has (its K is singular there) and which
    is what a mass matrix with massless DOFs passed as K looks like. The message names
    those DOFs and says that M and K may be swapped."""
    k_rows = np.asarray(abs(K).sum(axis=1)).ravel()
    m_rows = np.asarray(abs(M).sum(axis=1)).ravel()
    loose = np.flatnonzero((k_rows == 0) & (m_rows > 0))
    if not len(loose):
        return
    shown = loose[:10].tolist()
    more = f" and {len(loose) - 10} more" if len(loose) > 10 else ""
    massless = int(np.count_nonzero(m_rows == 0))
    raise ValueError(f"K is zero on the rows of DOFs {shown}{more}, where M is not: DOFs with mass and no "
                     f"stiffness (K singular), while M has {massless} zero row(s); M and K may be swapped: "
                     "Model.from_matrices takes the mass matrix first, then the stiffness matrix")


# the stops (single-contact names, amplitude DOF), the DOF partition and the linear modes
# are mixins of their own modules; the class holds the data, its builders and its identity
@dataclass(frozen=True, eq=False)
class Model(StopsMixin, PartitionMixin, ModesMixin):
    """A linear structure with rigid stops.

    Build it with :meth:`from_matrices` (or a beam's ``.model()``); the constructor
    does no validation of its own. With one contact, :attr:`contact_dof`, :attr:`gap` and
    :attr:`stop_side` are its data (the names of mmshbm 0.1); with several, :attr:`gap` is
    the smallest gap (the unit of amplitudes "in gaps") and :attr:`contacts` holds the rest.

    Attributes
    ----------
    M, K : scipy.sparse.csr_matrix, shape (n_dof, n_dof)
        Mass (kg, kg·m²) and stiffness (N/m, N·m/rad) matrices, symmetric.
    contacts : tuple of Contact
        The rigid stops (at least one).
    description : dict
        JSON-serialisable facts that let the model be rebuilt (e.g. beam data, and the
        ``transforms`` applied since).
    damping : scipy.sparse.csr_matrix or None, shape (n_dof, n_dof)
        Viscous damping matrix C (N·s/m), zero on the massless DOFs; None: undamped.
    friction : tuple of FrictionContact
        Coulomb friction contacts on massless DOFs (:meth:`with_friction`); empty: none.
    elements : tuple of Element
        Smooth or piecewise-linear nonlinear elements (:mod:`mmshbm.elements`, added by
        :meth:`with_element`); empty: none.
    """

    M: sp.csr_matrix
    K: sp.csr_matrix
    contacts: tuple
    description: dict = field(default_factory=dict)
    damping: sp.csr_matrix | None = None
    _amplitude_dof: int | None = None
    friction: tuple = ()
    elements: tuple = ()

    # ------------------------------------------------------------------ builders
    @classmethod
    def from_matrices(cls, M, K, contact_dof, gap, stop_side=1, description: dict | None = None, *,
                      damping=None, amplitude_dof: int | None = None) -> Model:
        """Build and validate a model from user matrices.

        Parameters
        ----------
        M, K : array_like or sparse, shape (n, n)
            Symmetric mass and stiffness matrices. DOFs whose mass row is zero are
            massless.
        contact_dof : int or sequence of int
            The DOF(s) facing a stop, ``0 <= contact_dof < n``. The same DOF may appear
            twice with opposite ``stop_side`` (a clearance). ``[]`` (with ``gap=[]``,
            ``stop_side=[]``): no unilateral contact (e.g. friction only,
            :meth:`with_friction`; name ``amplitude_dof``).
        gap : float or sequence of float
            Distance(s) (m) to the stop(s), >= 0: one for all contacts or one per contact.
        stop_side : {+1, -1} or sequence of them
            +1: stop at ``q[dof] = +gap``; -1: at ``-gap``; one for all or one per contact.
        description : dict, optional
            JSON-serialisable facts about the model.
        damping : array_like or sparse, shape (n, n), optional
            Viscous damping matrix C (N·s/m); its rows and columns of massless DOFs must
            be zero.
        amplitude_dof : int, optional
            The DOF whose largest excursion is a branch's amplitude. Default: the contact
            DOF when the model has a single contact; required otherwise (by the methods
            that report an amplitude).

        Raises
        ------
        ValueError, TypeError
            Naming the offending input: non-square, non-symmetric, non-finite or
            mismatched matrices; bad contact data (see
            :func:`~mmshbm.model.contact.contacts_from`); damping on a massless DOF; a
            singular or indefinite linear subsystem; M and K swapped
            (:func:`check_not_swapped`).
        """
        M = check.square_matrix("M", M)
        K = check.square_matrix("K", K)
        if M.shape != K.shape:
            raise ValueError(f"M and K must have the same shape, got {M.shape} and {K.shape}")
        check.symmetric("M", M)
        check.symmetric("K", K)
        check_not_swapped(M, K)
        n = M.shape[0]
        empty = no_contacts(contact_dof, gap, stop_side)
        contacts = () if empty else contacts_from(contact_dof, gap, stop_side, n)
        if damping is not None:
            damping = check.square_matrix("damping", damping)
            if damping.shape != M.shape:
                raise ValueError(f"damping must have the shape of M {M.shape}, got {damping.shape}")
        if amplitude_dof is not None:
            amplitude_dof = check.integer("amplitude_dof", amplitude_dof)
            if not 0 <= amplitude_dof < n:
                raise ValueError(f"amplitude_dof must be in [0, {n - 1}], got {amplitude_dof}")
        model = cls(M, K, contacts, dict(description or {}), damping, amplitude_dof)
        model._check_partition()
        return model

    @classmethod
    def from_npz(cls, path, contact_dof=None, gap=None, stop_side=None, *,
                 amplitude_dof: int | None = None) -> Model:
        """Load a model from a ``.npz`` file (format: :mod:`mmshbm.model.files`);
        arguments given here override the file's entries."""
        from .files import read_npz

        kwargs = read_npz(path, contact_dof, gap, stop_side, amplitude_dof)
        friction = kwargs.pop("friction", [])
        model = cls.from_matrices(**kwargs)
        if friction:
            from .friction import add_friction

            model = add_friction(model, friction)
        return model._with_recorded_elements()

    def _with_recorded_elements(self) -> Model:
        """The model with the elements its ``description["transforms"]`` records
        (:meth:`with_element`) when it has none: what a file that keeps the description
        but not the elements needs to get them back."""
        if self.elements:
            return self
        from ..elements import from_json

        elements = tuple(from_json(step["args"]["element"]) for step in self.description.get("transforms", [])
                         if step.get("name") == "with_element")
        return replace(self, elements=elements) if elements else self

    @classmethod
    def from_matrix_market(cls, M_path, K_path, contact_dof, gap, stop_side=1, *,
                           amplitude_dof: int | None = None) -> Model:
        """Load ``M`` and ``K`` from two Matrix Market (``.mtx``) files."""
        from .files import read_matrix_market

        M, K = read_matrix_market(M_path, K_path)
        return cls.from_matrices(M, K, contact_dof, gap, stop_side, amplitude_dof=amplitude_dof)

    def save_npz(self, path) -> None:
        """Write the model (CSR parts, contacts, damping, description) to ``path``."""
        from .files import write_npz

        write_npz(path, self)

    def with_gap(self, gap) -> Model:
        """The same structure with another gap (m): one number for every contact, or one per
        contact."""
        dofs, sides = [c.dof for c in self.contacts], [c.side for c in self.contacts]
        if len(dofs) == 1:
            dofs, sides = dofs[0], sides[0]
        contacts = contacts_from(dofs, gap, sides, self.n_dof)
        return replace(self, contacts=contacts)

    def with_damping(self, modal_ratio=None, rayleigh=None) -> Model:
        """The same structure with viscous damping on its DOFs with mass (replacing any
        damping it had); see :mod:`mmshbm.model.damping`.

        Parameters
        ----------
        modal_ratio : float or sequence of float, optional
            Damping ratio ζ >= 0 of every open-contact mode, or (ζ_1, ..., ζ_m) of the m
            lowest modes (the others undamped).
        rayleigh : (float, float), optional
            (α in 1/s, β in s) >= 0: C = α M + β K on the DOFs with mass (K with the
            massless DOFs condensed statically). Both forms
            given: their sum.

        Returns
        -------
        Model
            With ``damping`` set and the call recorded in ``description["transforms"]``.

        Raises
        ------
        ValueError, TypeError
            Neither form given, negative damping, more ratios than modes, a bad pair.
        """
        from .damping import damping_matrix

        C = damping_matrix(self, modal_ratio, rayleigh)
        args = {}
        if modal_ratio is not None:
            args["modal_ratio"] = (float(modal_ratio) if np.ndim(modal_ratio) == 0
                                   else [float(z) for z in np.ravel(modal_ratio)])
        if rayleigh is not None:
            args["rayleigh"] = [float(rayleigh[0]), float(rayleigh[1])]
        description = dict(self.description)
        description["transforms"] = list(description.get("transforms", [])) + [
            {"name": "with_damping", "args": args}]
        return replace(self, damping=C, description=description)

    def with_friction(self, dof: int, mu: float, *, normal_load: float | None = None,
                      normal_contact: int | None = None, preload: float | None = None,
                      tangential_stiffness: float | None = None) -> Model:
        """The same model with Coulomb friction (coefficient ``mu``) at ``dof``, pressed by a
        constant ``normal_load`` (N) or by unilateral contact ``normal_contact`` (plus
        ``preload``); several calls add several. With ``tangential_stiffness`` k_t (N/m) a
        massless slider (the new last DOF) is joined to ``dof`` by k_t and carries the
        friction (a Jenkins element: ``dof`` may carry mass); without it ``dof`` must be
        massless (rigid Coulomb). See :func:`mmshbm.model.friction.with_friction`
        (ValueError naming bad input)."""
        from .friction import with_friction

        return with_friction(self, dof, mu, normal_load, normal_contact, preload, tangential_stiffness)

    def with_element(self, element) -> Model:
        """The same model with the nonlinear ``element`` added (an
        :class:`~mmshbm.elements.Element`, e.g. ``mmshbm.elements.CubicSpring(dof=0,
        stiffness=k3)``, or its JSON form); several calls add several. The call is recorded
        in ``description["transforms"]``. A model without contacts measures its amplitude
        at the first element's first DOF unless it names an amplitude DOF.

        Raises
        ------
        TypeError, ValueError
            Not an element, or an element on a DOF the model does not have.
        """
        from ..elements import Element, from_json

        if isinstance(element, dict):
            element = from_json(element)
        if not isinstance(element, Element):
            raise TypeError(f"element must be an mmshbm.elements.Element (e.g. CubicSpring), "
                            f"got {type(element).__name__} {element!r}")
        element.check_model(self.n_dof)
        description = dict(self.description)
        description["transforms"] = list(description.get("transforms", [])) + [
            {"name": "with_element", "args": {"element": element.to_json()}}]
        amplitude_dof = self._amplitude_dof
        if amplitude_dof is None and not self.contacts:
            amplitude_dof = element.dofs[0]
        return replace(self, elements=self.elements + (element,), description=description,
                       _amplitude_dof=amplitude_dof)

    def with_amplitude_dof(self, dof: int) -> Model:
        """The same model with its amplitude measured at ``dof``."""
        dof = check.integer("amplitude_dof", dof)
        if not 0 <= dof < self.n_dof:
            raise ValueError(f"amplitude_dof must be in [0, {self.n_dof - 1}], got {dof}")
        return replace(self, _amplitude_dof=dof)

    def with_contact_layer(self, stiffness=None) -> Model:
        """The structure as it is, plus a massless contact node per contact joined to the
        contact DOF by a spring of ``stiffness`` (N/m; one, or one per contact; default 10⁵
        times the static stiffness at the contact), the stops moved onto the new nodes: a
        model MMS-HBM can run without removing any mass. See
        :func:`mmshbm.model.transforms.with_contact_layer`."""
        from .transforms import with_contact_layer

        return with_contact_layer(self, stiffness)

    def with_massless_contact(self, dofs=None) -> Model:
        """The model with the mass rows and columns of the contact node's DOFs (or ``dofs``)
        zeroed; warns (:class:`~mmshbm.ModelWarning`) and records in the description how much
        mass that removed and how far the lowest eigenfrequencies moved. See
        :func:`mmshbm.model.transforms.with_massless_contact`."""
        from .transforms import with_massless_contact

        return with_massless_contact(self, dofs)

    # ------------------------------------------------------------------ identity
    def fingerprint(self) -> str:
        """SHA-256 of the matrices (CSR parts), contacts, damping and amplitude DOF: equal
        fingerprints mean the same model (a checkpoint can only be resumed on it). A
        single undamped contact hashes as in mmshbm 0.1. Kept with the model (immutable)."""
        import hashlib
        import json

        digest = self.__dict__.get("_memo_fingerprint")
        if digest is not None:
            return digest
        h = hashlib.sha256()
        mats = [self.M, self.K] + ([self.damping] if self.damping is not None else [])
        for A in mats:
            A = sp.csr_matrix(A, copy=True)
            A.sort_indices()
            for part in (A.data, A.indices, A.indptr, np.array(A.shape)):
                kind = "<f8" if part.dtype.kind == "f" else "<i8"
                h.update(np.ascontiguousarray(part).astype(kind).tobytes())
        contacts = [[int(c.dof), float(c.gap).hex(), int(c.side)] for c in self.contacts]
        h.update(json.dumps(contacts[0] if len(contacts) == 1 else contacts).encode())
        if self._amplitude_dof is not None:
            h.update(json.dumps({"amplitude_dof": int(self._amplitude_dof)}).encode())
        if self.friction:
            from .friction import friction_to_json

            h.update(friction_to_json(self.friction).encode())
        if self.elements:
            h.update(json.dumps([e.to_json() for e in self.elements]).encode())
        digest = self.__dict__["_memo_fingerprint"] = h.hexdigest()
        return digest

    def same_as(self, other: Model) -> bool:
        """True when both models have identical matrices, contacts, damping and amplitude DOF."""
        if not isinstance(other, Model) or self.M.shape != other.M.shape:
            return False
        if (self.contacts != other.contacts or self._amplitude_dof != other._amplitude_dof
                or self.friction != other.friction or self.elements != other.elements):
            return False
        if (self.damping is None) != (other.damping is None):
            return False
        pairs = [(self.M, other.M), (self.K, other.K)]
        if self.damping is not None:
            pairs.append((self.damping, other.damping))
        return all((sp.csr_matrix(A) != sp.csr_matrix(B)).nnz == 0 for A, B in pairs)

    def __repr__(self) -> str:
        if len(self.contacts) == 1:
            contact = (f"contact_dof={self.contact_dof}, gap={self.gap:g}, stop_side={self.stop_side:+d}")
        else:
            contact = "contacts=[" + ", ".join(f"(dof {c.dof}, gap {c.gap:g}, side {c.side:+d})"
                                               for c in self.contacts) + "]"
        extra = "" if self.damping is None else ", damped"
        if self.friction:
            extra += ", friction on DOFs " + str([fc.dof for fc in self.friction])
        if self.elements:
            extra += ", elements [" + ", ".join(f"{e.kind} on {list(e.dofs)}" for e in self.elements) + "]"
        return f"Model(n_dof={self.n_dof}, massless={self.c.tolist()}, {contact}{extra})"
