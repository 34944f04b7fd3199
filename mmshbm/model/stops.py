"""The stops of a :class:`~mmshbm.model.Model` seen from the model: the names of a single
contact, the amplitude DOF and how far it can swing, and whether the contact DOFs are
massless (a mixin of the model)."""

from __future__ import annotations

from functools import cached_property

import numpy as np

from .contact import Contact

__all__ = ["StopsMixin"]


class StopsMixin:
    """The model's contacts as attributes (needs the attributes of
    :class:`~mmshbm.model.Model`: ``contacts``, ``_amplitude_dof``, ``M``, ``K``, and the
    partition ``c``, ``l``)."""

    # ------------------------------------------------------------------ contacts
    @property
    def n_contacts(self) -> int:
        """Number of contacts (stops)."""
        return len(self.contacts)

    def _single(self, what: str) -> Contact:
        if len(self.contacts) != 1:
            raise ValueError(f"the model has {len(self.contacts)} contacts, so it has no single {what}: "
                             "use model.contacts")
        return self.contacts[0]

    @property
    def contact_dof(self) -> int:
        """The contact DOF of a single-contact model (ValueError with several)."""
        return self._single("contact_dof").dof

    @property
    def stop_side(self) -> int:
        """The stop side (±1) of a single-contact model (ValueError with several)."""
        return self._single("stop_side").side

    @property
    def gap(self) -> float:
        """The gap (m) of a single-contact model; with several, the smallest positive one
        (the unit of amplitudes "in gaps"; 0 if all are 0)."""
        gaps = [c.gap for c in self.contacts]
        positive = [g for g in gaps if g > 0]
        return min(positive) if positive else 0.0

    @property
    def contact_dofs(self) -> tuple:
        """The DOF of each contact (a DOF appears twice in a clearance)."""
        return tuple(c.dof for c in self.contacts)

    @property
    def amplitude_dof(self) -> int:
        """The DOF whose largest excursion is the amplitude of a branch: the one given, the
        contact DOF of a single-contact model, or, with several contacts (a clearance: a
        massless DOF between two stops never passes them), the DOF with mass most strongly
        coupled to the contacts (:attr:`_coupled_dof`)."""
        if self._amplitude_dof is not None:
            return self._amplitude_dof
        if len(self.contacts) == 1:
            return self.contacts[0].dof
        return self._coupled_dof

    @property
    def amplitude_limit(self) -> float:
        """The largest amplitude (m) the amplitude DOF can have: +inf, except for a massless
        DOF between two stops (it never passes them: the farther stop's distance)."""
        dof = self.amplitude_dof
        gaps = {ct.side: ct.gap for ct in self.contacts if ct.dof == dof}
        if len(gaps) < 2 or dof not in set(self.c.tolist()):
            return float("inf")
        return float(max(gaps.values()))

    def check_amplitude_reach(self, max_amplitude: float) -> None:
        """Raise a ValueError when the amplitude DOF cannot reach ``max_amplitude`` (m)."""
        limit = self.amplitude_limit
        if max_amplitude > limit * (1 + 1e-9):
            dof = self.amplitude_dof
            raise ValueError(
                f"amplitude_dof {dof} is massless and held between two stops: its amplitude never exceeds "
                f"{limit:g} m, so max_amplitude = {max_amplitude:g} m cannot be reached; measure the "
                f"amplitude at a DOF with mass (model.with_amplitude_dof(dof), e.g. DOF {self._coupled_dof}, "
                "the default with several contacts)")

    @cached_property
    def _coupled_dof(self) -> int:
        """The DOF with mass most strongly coupled to the contacts: the largest
        √M_ii·|z_i| over the DOFs with mass, z the static displacement of those DOFs when
        every contact DOF moves by one unit toward its stop with the other massless DOFs
        free (√M_ii·|z_i| is that DOF's share of the root kinetic energy, comparable
        across translations and rotations)."""
        l, c = self.l, self.c
        if not len(l):
            raise ValueError("the model has no DOF with mass to measure the amplitude at")
        dofs = sorted({ct.dof for ct in self.contacts})
        K = self.K.tocsr()
        free = np.array([i for i in c if i not in dofs] + list(l), dtype=int)
        K_ff = K[free][:, free].toarray()
        K_fd = K[free][:, dofs].toarray()
        # every contact DOF displaced by one unit (its stop's side): the others follow statically
        side = np.array([next(ct.side for ct in self.contacts if ct.dof == d) for d in dofs], dtype=float)
        z = -np.linalg.lstsq(K_ff, K_fd @ side, rcond=None)[0]
        mass = np.asarray(self.M.tocsr().diagonal())[free]
        score = np.where(mass > 0, np.sqrt(np.abs(mass)) * np.abs(z), -1.0)
        return int(free[int(np.argmax(score))])

    @property
    def massless_contacts(self) -> bool:
        """True when every contact DOF is massless (what MMS-HBM and the exact reference
        need)."""
        c = set(self.c.tolist())
        return all(ct.dof in c for ct in self.contacts)

    def require_massless_contacts(self, who: str) -> None:
        """Raise a ValueError naming the conversions unless every contact DOF is massless.

        ``who`` names the method that needs it (e.g. ``"MMS-HBM"``)."""
        c = set(self.c.tolist())
        heavy = sorted({ct.dof for ct in self.contacts if ct.dof not in c})
        if heavy:
            many = len(heavy) > 1
            raise ValueError(
                f"contact DOF{'s' if many else ''} {heavy} carr{'y' if many else 'ies'} mass, "
                f"but {who} needs massless contact DOFs (their equations are static): convert the model "
                "with model.with_contact_layer(stiffness) (a massless contact node joined by a spring, the "
                "mass kept) or model.with_massless_contact() (the contact node's mass removed), or use "
                "method='penalty'")

