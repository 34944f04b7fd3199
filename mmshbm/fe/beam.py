"""The benchmark structure: a clamped Timoshenko beam of rectangular section hitting a stop at its tip.

:class:`TimoshenkoBeam` holds the beam's data (SI units) and builds the finite-element
:class:`~mmshbm.model.Model`: interdependent-interpolation Timoshenko elements
(:mod:`mmshbm.fe.element`) on a mesh graded toward the tip (:mod:`mmshbm.fe.mesh`),
assembled (:mod:`mmshbm.fe.assembly`), clamped at the root, with the tip node made
massless so that the contact DOFs follow the rest statically.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numpy as np
import scipy.sparse as sp

from .. import _validate as check
from ..model.model import Model
from . import assembly, element, mesh

__all__ = ["TimoshenkoBeam", "default_beam"]

# β_n L of the clamped-free Euler–Bernoulli beam (roots of cos βL cosh βL = −1)
_EB_CLAMPED_FREE = (1.8751040687119611, 4.6940911329741745, 7.8547574382376126, 10.995540734875467)


@dataclass(frozen=True)
class TimoshenkoBeam:
    """A straight beam of rectangular section, clamped at x = 0, with a stop under its tip.

    Parameters
    ----------
    length : float
        Beam length L (m).
    width, height : float
        Section width b and height h (m); bending is about the axis parallel to ``width``
        (the tip moves along ``height``).
    E : float
        Young's modulus (Pa).
    rho : float
        Density (kg/m³).
    nu : float
        Poisson's ratio, in (−1, 0.5); sets G = E / (2 (1 + ν)).
    shear_factor : float
        Shear correction factor κ > 0 (5/6 for a rectangle).
    gap : float
        Distance (m) from the tip's rest position to the stop, >= 0. The stop is on the
        positive side of the tip deflection (``stop_side = +1``).

    Raises
    ------
    ValueError, TypeError
        For a non-positive dimension or material constant, ν outside (−1, 0.5), κ <= 0 or
        a negative gap; the message names the field and its value.
    """

    length: float
    width: float
    height: float
    E: float
    rho: float
    nu: float = 0.3
    shear_factor: float = 5.0 / 6.0
    gap: float = 1e-3

    def __post_init__(self):
        for name in ("length", "width", "height", "E", "rho", "shear_factor"):
            object.__setattr__(self, name, check.positive(name, getattr(self, name)))
        nu = check.real_number("nu", self.nu)
        if not -1.0 < nu < 0.5:
            raise ValueError(f"nu must be in (-1, 0.5), got {self.nu!r}")
        object.__setattr__(self, "nu", nu)
        object.__setattr__(self, "gap", check.non_negative("gap", self.gap))

    # ------------------------------------------------------------------ section
    @property
    def area(self) -> float:
        """Cross-section area A = b h (m²)."""
        return self.width * self.height

    @property
    def inertia(self) -> float:
        """Second moment of area I = b h³ / 12 (m⁴)."""
        return self.width * self.height**3 / 12.0

    @property
    def shear_modulus(self) -> float:
        """G = E / (2 (1 + ν)) (Pa)."""
        return self.E / (2.0 * (1.0 + self.nu))

    def section(self) -> dict:
        """Section and material constants as passed to :mod:`mmshbm.fe.element`:
        ``E, G`` (Pa), ``rho`` (kg/m³), ``A`` (m²), ``I`` (m⁴), ``kappa``."""
        return {"E": self.E, "G": self.shear_modulus, "rho": self.rho, "A": self.area,
                "I": self.inertia, "kappa": self.shear_factor}

    # ------------------------------------------------------------------ mesh and matrices
    def element_lengths(self, n_elements: int, grading: float = 10.0) -> np.ndarray:
        """Element lengths (m), root first, shape (n_elements,); see :func:`mesh.graded_lengths`."""
        return mesh.graded_lengths(self.length, n_elements, grading)

    def node_coordinates(self, n_elements: int, grading: float = 10.0) -> np.ndarray:
        """Node positions (m) from root to tip, shape (n_elements + 1,)."""
        return mesh.node_coordinates(self.element_lengths(n_elements, grading))

    def matrices(self, n_elements: int, grading: float = 10.0,
                 clamped: bool = True) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """Assembled mass and stiffness matrices.

        Parameters
        ----------
        n_elements : int
            Number of elements, >= 1.
        grading : float
            Root-to-tip element length ratio, > 0 (1.0 = uniform).
        clamped : bool
            If True remove the root's DOFs: order ``[w1, θ1, ..., wn, θn]``, size 2n.
            If False the free-free matrices, order ``[w0, θ0, ..., wn, θn]``, size 2n + 2.

        Returns
        -------
        M, K : scipy.sparse.csr_matrix
            Consistent mass (kg, kg·m, kg·m²) and stiffness (N/m, N, N·m/rad).
        """
        Ke, Me = element.element_matrices(self.element_lengths(n_elements, grading), **self.section())
        dofs = assembly.chain_dofs(len(Ke))
        M = assembly.assemble(Me, dofs)
        K = assembly.assemble(Ke, dofs)
        if clamped:
            root = assembly.clamped_root_dofs()
            M, K = assembly.remove_dofs(M, root), assembly.remove_dofs(K, root)
        return M, K

    @staticmethod
    def tip_dofs(n_elements: int) -> tuple[int, int]:
        """(tip deflection, tip rotation) DOF indices of the clamped model: (2n − 2, 2n − 1)."""
        return 2 * n_elements - 2, 2 * n_elements - 1

    def model(self, n_elements: int, grading: float = 10.0, massless_tip: bool = True) -> Model:
        """The clamped beam as a :class:`~mmshbm.model.Model` with the stop at its tip.

        Parameters
        ----------
        n_elements : int
            Number of elements, >= 1 (the paper uses 8 and 21).
        grading : float
            Ratio of the root to the tip element length, > 0 (1.0 = uniform).
        massless_tip : bool
            If True (the MMS-HBM model) zero the mass rows and columns of both tip DOFs,
            which become the massless contact DOFs. If False keep the consistent mass
            everywhere: the model is then for linear modes only (the solvers need a
            massless contact DOF) and is built without :meth:`Model.from_matrices`'
            partition checks.

        Returns
        -------
        Model
            DOFs ``[w1, θ1, ..., wn, θn]``, ``contact_dof = 2n − 2`` (tip deflection),
            ``stop_side = +1``, ``gap = self.gap``; ``description`` holds everything
            :meth:`rebuild` needs.
        """
        n = check.integer("n_elements", n_elements, minimum=1)
        grading = check.positive("grading", grading)
        if not isinstance(massless_tip, bool | np.bool_):
            raise TypeError(f"massless_tip must be a bool, got {type(massless_tip).__name__} "
                            f"{massless_tip!r}")
        M, K = self.matrices(n, grading, clamped=True)
        contact_dof, _ = self.tip_dofs(n)
        description = {"kind": "TimoshenkoBeam", **asdict(self), "n_elements": n,
                       "grading": grading, "massless_tip": bool(massless_tip)}
        if massless_tip:
            keep = np.ones(M.shape[0])
            keep[list(self.tip_dofs(n))] = 0.0
            D = sp.diags(keep, format="csr")
            M = (D @ M @ D).tocsr()
            M.eliminate_zeros()
            return Model.from_matrices(M, K, contact_dof=contact_dof, gap=self.gap, stop_side=+1,
                                       description=description)
        return Model.from_matrices(M, K, contact_dof=contact_dof, gap=self.gap, stop_side=+1,
                                   description=description)

    def solid_model(self, n_length: int = 40, n_width: int = 2, n_height: int = 2, grading: float = 10.0,
                    order: int = 2, massless_tip: bool = True) -> Model:
        """This beam as a 3-D solid (scikit-fem hexahedra): clamped root face, massless tip
        layer, a rigid plane under the tip face with one contact per tip-face node's vertical
        DOF; see :func:`mmshbm.fe.solid.solid_beam_model` for the parameters."""
        from .solid import solid_beam_model

        return solid_beam_model(self, n_length, n_width, n_height, grading, order, massless_tip)

    @classmethod
    def rebuild(cls, description: dict) -> Model:
        """Rebuild a model from the ``description`` of :meth:`model` (e.g. loaded from a file)."""
        if description.get("kind") != "TimoshenkoBeam":
            raise ValueError("description is not of a TimoshenkoBeam model: "
                             f"kind={description.get('kind')!r}")
        try:
            beam = cls(**{f.name: description[f.name] for f in fields(cls)})
            return beam.model(description["n_elements"], description["grading"],
                              description["massless_tip"])
        except KeyError as err:
            raise ValueError(f"description lacks the entry {err.args[0]!r}") from None

    # ------------------------------------------------------------------ closed forms
    def euler_bernoulli_frequencies(self, n: int = 4) -> np.ndarray:
        """Clamped-free Euler–Bernoulli frequencies (Hz) of the ``n`` lowest modes.

        f_k = (β_k L)² / (2π L²) · √(E I / (ρ A)), with β_k L = 1.87510407, 4.69409113,
        7.85475744, 10.99554073 and (2k − 1) π / 2 beyond (exact to < 1e-8 there). Shear
        and rotary inertia are neglected, so this overestimates a stubby beam.
        """
        n = check.integer("n", n, minimum=1)
        k = np.arange(1, n + 1)
        bl = (2 * k - 1) * np.pi / 2
        m = min(n, len(_EB_CLAMPED_FREE))
        bl[:m] = _EB_CLAMPED_FREE[:m]
        c = np.sqrt(self.E * self.inertia / (self.rho * self.area))
        return bl**2 / self.length**2 * c / (2 * np.pi)


def default_beam(**overrides) -> TimoshenkoBeam:
    """The benchmark beam: steel, L = 0.5 m, b = 20 mm, h = 13.5 mm, E = 210 GPa,
    ρ = 7850 kg/m³, ν = 0.3, κ = 5/6, gap = 1 mm; ``overrides`` replace any of these
    fields (``default_beam(E=200e9, gap=2e-3)``), validated as the constructor validates.

    Raises
    ------
    TypeError
        For a name that is not a field of :class:`TimoshenkoBeam` (the fields are listed).
    """
    values = {"length": 0.5, "width": 0.020, "height": 0.0135, "E": 210e9, "rho": 7850.0, "nu": 0.3,
              "shear_factor": 5.0 / 6.0, "gap": 1e-3}
    names = [f.name for f in fields(TimoshenkoBeam)]
    unknown = sorted(set(overrides) - set(names))
    if unknown:
        raise TypeError(f"default_beam() got unknown field{'s' * (len(unknown) > 1)} {', '.join(unknown)}; "
                        f"the beam's fields: {', '.join(names)}")
    return TimoshenkoBeam(**(values | overrides))
