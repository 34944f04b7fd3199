"""Module paths of earlier releases, importable as the modules that now hold their code.

0.1 had flat modules (``mmshbm.exact``, ``mmshbm.studies``, ``mmshbm.baselines.shooting``,
...); the code now lives in layered packages. :class:`AliasFinder`, first on
``sys.meta_path``, answers an import of an old path (or of a submodule below it) with the
module of the new path itself, so ``import mmshbm.exact`` and
``from mmshbm.exact import periodic_orbit`` work and ``mmshbm.exact is mmshbm.methods.exact``:
one module object, one set of classes, nothing imported before it is asked for.
"""

from __future__ import annotations

import importlib
import sys

#: old dotted path -> the module that holds its code now (a prefix maps its submodules too)
MODULE_ALIASES = {
    "mmshbm.exact": "mmshbm.methods.exact",
    "mmshbm.api": "mmshbm.methods.backbone",
    "mmshbm.baselines": "mmshbm.methods",
    "mmshbm.benchmarking": "mmshbm.analysis.benchmarking",
    "mmshbm.checkpoint": "mmshbm.core.checkpoint",
    "mmshbm.condense": "mmshbm.core.condense",
    "mmshbm.continuation": "mmshbm.core.continuation",
    "mmshbm.examples": "mmshbm.fe.oscillator",
    "mmshbm.harmonics": "mmshbm.core.harmonics",
    "mmshbm.identification": "mmshbm.analysis.identification",
    "mmshbm.kernels": "mmshbm.core.kernels",
    "mmshbm.measured": "mmshbm.analysis.measured",
    "mmshbm.mms_hbm": "mmshbm.methods.mms.conservative",
    "mmshbm.studies": "mmshbm.analysis.studies",
    # 0.2 kept the methods side by side; they are grouped by method now
    "mmshbm.methods.mms_hbm": "mmshbm.methods.mms.conservative",
    "mmshbm.methods.mms_hbm_family": "mmshbm.methods.mms.family",
    "mmshbm.methods.mms_hbm_signals": "mmshbm.methods.mms.signals",
    "mmshbm.methods._damped_hbm": "mmshbm.methods.mms.damped",
    "mmshbm.methods.forced": "mmshbm.methods.mms.forced",
    "mmshbm.methods.epmc": "mmshbm.methods.mms.epmc",
    "mmshbm.methods.phase_resonance": "mmshbm.methods.mms.phase_resonance",
    "mmshbm.methods.stability": "mmshbm.methods.mms.stability",
    "mmshbm.methods.filtered": "mmshbm.methods.mms.filtered",
    "mmshbm.methods.friction_forced": "mmshbm.methods.mms.friction_forced",
    "mmshbm.methods.friction_epmc": "mmshbm.methods.mms.friction_epmc",
    "mmshbm.methods.friction_stability": "mmshbm.methods.mms.friction_stability",
    "mmshbm.methods.penalty_hbm": "mmshbm.methods.penalty.hbm",
    "mmshbm.methods.penalty_forced": "mmshbm.methods.penalty.forced",
    "mmshbm.methods.penalty_reduced": "mmshbm.methods.penalty.reduced",
    "mmshbm.methods._penalty_kernels": "mmshbm.methods.penalty._kernels",
    "mmshbm.methods._penalty_reduced_kernels": "mmshbm.methods.penalty._reduced_kernels",
    "mmshbm.methods.friction_penalty": "mmshbm.methods.penalty.jenkins",
    "mmshbm.methods.shooting_forced": "mmshbm.methods.shooting.forced",
    "mmshbm.methods._shooting_kernels": "mmshbm.methods.shooting._kernels",
    "mmshbm.methods._shooting_contact_kernels": "mmshbm.methods.shooting._contact_kernels",
    "mmshbm.methods._forced_shooting_kernels": "mmshbm.methods.shooting._forced_kernels",
    "mmshbm.methods._shooting_signals": "mmshbm.methods.shooting.signals",
    "mmshbm.methods.friction_shooting": "mmshbm.methods.shooting.friction",
    "mmshbm.methods.friction_impact": "mmshbm.methods.shooting.friction_impact",
    # the contact laws' data and static problem live with the laws
    "mmshbm.methods._contacts": "mmshbm.contact.table",
    "mmshbm.methods.signals": "mmshbm.contact.static",
}


def target(fullname: str) -> str | None:
    """The module that an old dotted path stands for, or None if it is not an old path."""
    if not fullname.startswith("mmshbm."):
        return None
    for old, new in MODULE_ALIASES.items():
        if fullname == old or fullname.startswith(old + "."):
            return new + fullname[len(old):]
    return None


class AliasFinder:
    """Finds old module paths; loading one puts the new module in ``sys.modules`` under the
    old name (the import machinery then returns what ``sys.modules`` holds). A meta-path
    finder and loader by protocol (importlib.abc costs milliseconds to import)."""

    def find_spec(self, fullname, path=None, target_=None):
        new = target(fullname)
        if new is None:
            return None
        import importlib.util

        if importlib.util.find_spec(new) is None:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec):
        return None

    def exec_module(self, module) -> None:
        sys.modules[module.__name__] = importlib.import_module(target(module.__name__))


def install() -> None:
    """Put one AliasFinder first on ``sys.meta_path`` (idempotent)."""
    if not any(isinstance(f, AliasFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, AliasFinder())
