"""What each method is and can do, by name: the capability table that every switch on a
method's name reads (the methods layer's registry, :mod:`mmshbm.methods.registry`, holds
the problem classes of the same names and re-uses this table). Plain data, importable
from any layer without importing numpy."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["DEFAULT_METHOD", "MethodInfo", "METHOD_INFO", "method_info", "is_harmonic_balance",
           "backbone_methods", "forced_methods", "benchmarked_methods"]


@dataclass(frozen=True)
class MethodInfo:
    """What a method is and can do, read by every switch on a method's name.

    display_name : str
        The name in tables and summaries ("MMS-HBM", "penalty-HBM", ...).
    harmonic_balance : bool
        Unknowns are Fourier coefficients up to H (takes ``harmonics``); False for the
        time-domain methods.
    memory_model : {"condensed", "assembled", "time-march"}
        Which memory estimate of :func:`mmshbm.methods.limits.estimate_memory` applies
        (unknowns on the condensed DOFs, on every DOF with an assembled sparse Jacobian per
        harmonic, or a time march).
    baseline : bool
        A comparison method (the CLI exits 1 when its branch turns into another family).
    proximal_parameter : bool
        Takes the proximal parameter ``r`` (the CLI's ``--proximal``).
    cheap_truncation_estimate : bool
        Its truncation estimate (re-solves at 2H and 4H) is cheap enough to show in a summary.
    cli_backbone : bool
        Offered by ``mmshbm backbone --method`` and ``mmshbm study --methods``.
    forced : bool
        Has a forced-response problem (:func:`mmshbm.frequency_response`, ``mmshbm frf``).
    damped_variant : str or None
        The method that computes this one's backbone on a damped model (or one with friction).
    floquet_trivial : int
        Trivial Floquet multipliers of its periodic orbits when it offers their stability
        (:func:`mmshbm.branch_stability`): 2 for a conservative flow (time shift and energy),
        1 for a damped mode's flow; 0: it offers none.
    resolution : str or None
        What ``mmshbm bench`` tunes to reach a target accuracy: "harmonics" (H),
        "harmonics and penalty" (H and k_p), "time steps" (steps per period); None: the
        method is not benchmarked.
    """

    display_name: str
    harmonic_balance: bool = True
    memory_model: str = "condensed"
    baseline: bool = True
    proximal_parameter: bool = False
    cheap_truncation_estimate: bool = False
    cli_backbone: bool = False
    forced: bool = False
    damped_variant: str | None = None
    floquet_trivial: int = 0
    resolution: str | None = None


#: the method of ``mmshbm.backbone`` and ``frequency_response`` when none is named
DEFAULT_METHOD = "mmshbm"

#: method name -> its capabilities (every name of :data:`METHODS`)
METHOD_INFO = {
    "mmshbm": MethodInfo("MMS-HBM", baseline=False, proximal_parameter=True, cheap_truncation_estimate=True,
                         cli_backbone=True, forced=True, damped_variant="epmc", floquet_trivial=2,
                         resolution="harmonics"),
    "penalty": MethodInfo("penalty-HBM", memory_model="assembled", cli_backbone=True, forced=True,
                          resolution="harmonics and penalty"),
    "penalty-reduced": MethodInfo("penalty-HBM (reduced)", cli_backbone=True),
    "shooting": MethodInfo("shooting", harmonic_balance=False, memory_model="time-march", cli_backbone=True,
                           forced=True, resolution="time steps"),
    "epmc": MethodInfo("EPMC", baseline=False, floquet_trivial=1),
    "phase_resonance": MethodInfo("phase resonance", baseline=False),
}


def method_info(method: str) -> MethodInfo:
    """The capabilities of ``method`` (a :class:`MethodInfo`); an unknown name gets those of
    a harmonic-balance method with none of the options (its name is checked where it is run)."""
    info = METHOD_INFO.get(method)
    return info if info is not None else MethodInfo(str(method), baseline=False)


def is_harmonic_balance(method: str) -> bool:
    """Whether ``method``'s unknowns are Fourier coefficients (it takes ``harmonics``)."""
    return method_info(method).harmonic_balance


def backbone_methods() -> list[str]:
    """The methods the CLI offers for a backbone (``mmshbm backbone``, ``mmshbm study``)."""
    return [name for name, info in METHOD_INFO.items() if info.cli_backbone]


def benchmarked_methods() -> list[str]:
    """The methods ``mmshbm bench`` compares (those with a :attr:`MethodInfo.resolution`)."""
    return [name for name, info in METHOD_INFO.items() if info.resolution is not None]


def forced_methods() -> list[str]:
    """The methods with a forced-response problem (``mmshbm frf``)."""
    return [name for name, info in METHOD_INFO.items() if info.forced]
