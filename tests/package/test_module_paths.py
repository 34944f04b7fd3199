"""The public contract of ``mmshbm``'s top level: every name in ``mmshbm.__all__`` resolves
(lazily), ``mmshbm.exact`` is the exact reference, ``import mmshbm`` loads none of the heavy
libraries, and the module paths and names of earlier releases are gone (CHANGELOG.md says what
replaces each)."""

from __future__ import annotations

import importlib
import pathlib
import subprocess
import sys

import pytest

import mmshbm

#: module paths of 0.1 and 0.2 (flat modules, methods side by side, the contact laws'
#: old homes); each now raises ModuleNotFoundError
OLD_PATHS = [
    "mmshbm.api", "mmshbm.baselines", "mmshbm.baselines.shooting", "mmshbm.benchmarking",
    "mmshbm.checkpoint", "mmshbm.condense", "mmshbm.continuation", "mmshbm.examples", "mmshbm.harmonics",
    "mmshbm.identification", "mmshbm.kernels", "mmshbm.measured", "mmshbm.mms_hbm", "mmshbm.studies",
    "mmshbm.methods.mms_hbm", "mmshbm.methods.mms_hbm_family", "mmshbm.methods.mms_hbm_signals",
    "mmshbm.methods._damped_hbm", "mmshbm.methods.forced", "mmshbm.methods.epmc",
    "mmshbm.methods.phase_resonance", "mmshbm.methods.stability", "mmshbm.methods.filtered",
    "mmshbm.methods.friction_forced", "mmshbm.methods.friction_epmc", "mmshbm.methods.friction_stability",
    "mmshbm.methods.penalty_hbm", "mmshbm.methods.penalty_forced", "mmshbm.methods.penalty_reduced",
    "mmshbm.methods._penalty_kernels", "mmshbm.methods._penalty_reduced_kernels",
    "mmshbm.methods.friction_penalty", "mmshbm.methods.shooting_forced", "mmshbm.methods._shooting_kernels",
    "mmshbm.methods._shooting_contact_kernels", "mmshbm.methods._forced_shooting_kernels",
    "mmshbm.methods._shooting_signals", "mmshbm.methods.friction_shooting", "mmshbm.methods.friction_impact",
    "mmshbm.methods._contacts", "mmshbm.methods.signals", "mmshbm.core.projection",
]

#: the flat submodule attributes of 0.1 on ``mmshbm`` (``mmshbm.studies``, ...)
OLD_ATTRIBUTES = ["harmonics", "kernels", "condense", "continuation", "checkpoint", "mms_hbm", "api",
                  "examples", "studies", "benchmarking", "identification", "measured"]

#: module -> names that were re-exported there for old import paths only
OLD_REEXPORTS = {
    "mmshbm.harmonic.kernels": ["proximal_contact", "cosine_product_matrix"],
    "mmshbm.core.continuation": ["_bordered_solve", "SKIP_MIN_TOL"],
    "mmshbm.methods.backbone": ["method_options", "_CONTINUATION_FIELDS"],
    "mmshbm.methods.mms.conservative": ["_mean_energy", "_held_frequency_solve", "_compute_tables"],
    "mmshbm.methods.shooting": ["ShootingProblem"],
    "mmshbm.methods.shooting._contact_kernels": ["lcp_solve"],
    "mmshbm.plotting.studies": ["plot_convergence", "plot_family_grid"],
}

#: the layered packages reachable as attributes of ``mmshbm``
PACKAGES = ["model", "fe", "core", "results", "methods", "analysis", "io", "plotting", "cli", "elements"]


@pytest.mark.parametrize("name", sorted(set(mmshbm.__all__) - {"__version__", "elements"}))
def test_every_public_name_resolves(name):
    value = getattr(mmshbm, name)
    assert value is not None
    module = importlib.import_module(mmshbm._LAZY[name])
    assert value is getattr(module, name)


def test_version_and_dir():
    assert isinstance(mmshbm.__version__, str)
    names = dir(mmshbm)
    assert set(mmshbm.__all__) | set(PACKAGES) | {"exact"} <= set(names)
    assert names == sorted(names)


def test_packages_are_attributes():
    for name in PACKAGES:
        assert getattr(mmshbm, name) is importlib.import_module(f"mmshbm.{name}")


def test_exact_is_the_exact_reference():
    import mmshbm.exact as imported
    from mmshbm import exact
    from mmshbm.methods import exact as methods_exact

    assert mmshbm.exact is exact is imported
    assert set(exact.__all__) == set(methods_exact.__all__)
    assert all(getattr(exact, name) is getattr(methods_exact, name) for name in exact.__all__)
    osc = mmshbm.OneDofOscillator(m=1.0, k1=1.0, k2=4.0, gap=1.0)
    orbit = mmshbm.exact.periodic_orbit(osc.model(), amplitude=2.0)
    # the oscillator's closed-form period (one contact per period); both are closed forms
    # whose phase times are solved to round-off
    assert orbit.converged and abs(orbit.period / osc.period(2.0) - 1) < 1e-12


def test_import_is_cheap():
    """A fresh interpreter importing mmshbm loads none of numba, scipy, matplotlib, pyfftw."""
    code = ("import sys, mmshbm; heavy = ('numba', 'scipy', 'matplotlib', 'pyfftw');"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in heavy))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


@pytest.mark.parametrize("path", OLD_PATHS)
def test_old_module_paths_are_gone(path):
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module(path)


def test_no_alias_finder():
    """The finder that answered old paths is gone from the package and from sys.meta_path
    (checked by file: an editable install's own finder may map any name it once saw)."""
    assert not (pathlib.Path(mmshbm.__file__).parent / "_aliases.py").exists()
    assert not any(type(f).__name__ == "AliasFinder" for f in sys.meta_path)


def test_old_attributes_are_gone():
    for name in OLD_ATTRIBUTES:
        assert not hasattr(mmshbm, name), name
        assert name not in dir(mmshbm)


@pytest.mark.parametrize("module", sorted(OLD_REEXPORTS))
def test_old_reexports_are_gone(module):
    loaded = importlib.import_module(module)
    for name in OLD_REEXPORTS[module]:
        assert not hasattr(loaded, name), f"{module}.{name}"
