"""Module paths and names of earlier releases keep working: every public function and class
that a 0.1 module defined is importable from that module's old dotted path, as the same
object the layered package holds now; ``dir(mmshbm)`` lists the lazy names."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

import mmshbm

#: 0.1 module path -> public functions and classes it defined (read from its source at the
#: last commit before the layered packages; loggers left out)
OLD_NAMES = {
    "mmshbm.exact": ["Phase", "PiecewiseLinearSystem", "Event", "Trajectory", "integrate", "PeriodicOrbit",
                     "periodic_orbit", "Backbone", "backbone"],
    "mmshbm.api": ["make_problem", "method_options", "backbone"],
    "mmshbm.studies": ["RunSpec", "build_model", "execute", "Study", "FrequencyTable", "ConvergenceFit",
                       "format_convergence", "run_study", "grid_specs", "figure2_study"],
    "mmshbm.baselines.shooting": ["ShootingProblem"],
    "mmshbm.baselines.penalty_hbm": ["PenaltyHBMProblem", "penalty_n_samples"],
    "mmshbm.continuation": ["ContinuationProblem", "ContinuationOptions", "ContinuationResult",
                            "ContinuationState", "newton", "continue_branch"],
    "mmshbm.condense": ["SingularDynamicStiffness", "Condensation"],
    "mmshbm.harmonics": ["check_harmonics", "default_n_samples", "HarmonicTransform", "transform"],
    "mmshbm.kernels": ["proximal_contact", "cosine_product_matrix"],
    "mmshbm.checkpoint": ["model_fingerprint", "Checkpoint", "read_checkpoint", "CheckpointWriter"],
    "mmshbm.mms_hbm": ["MMSHBMProblem"],
    "mmshbm.examples": ["OneDofOscillator", "one_dof_oscillator"],
    "mmshbm.benchmarking": ["load_model", "compare_methods", "format_table", "write_results",
                            "element_scaling", "format_scaling"],
    "mmshbm.identification": ["FitReport", "beam_frequencies", "fit_material"],
    "mmshbm.measured": ["MeasuredBackbone", "load_measured"],
    "mmshbm.model": ["Model"],
    # ``load`` read a Branch or a Study: it is ``mmshbm.load`` now (results sit below studies)
    "mmshbm.results": ["Branch", "rebuild_model", "versions", "branch_payload", "branch_from_payload",
                       "write_archive", "read_archive"],
}


@pytest.mark.parametrize("path", sorted(OLD_NAMES))
def test_old_module_path_imports(path):
    module = importlib.import_module(path)
    for name in OLD_NAMES[path]:
        assert hasattr(module, name), f"{path}.{name}"


def test_old_path_is_the_same_module_object():
    import mmshbm.exact
    from mmshbm.exact import periodic_orbit

    from mmshbm.methods import exact

    assert mmshbm.exact is exact and periodic_orbit is exact.periodic_orbit
    import mmshbm.exact.orbits

    assert mmshbm.exact.orbits is importlib.import_module("mmshbm.methods.exact.orbits")


def test_unknown_paths_still_fail():
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("mmshbm.no_such_module")
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("mmshbm.exact.no_such_module")


def test_old_path_in_a_fresh_interpreter():
    code = "from mmshbm.exact import periodic_orbit; import mmshbm.exact as e; print(e.__name__)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "mmshbm.methods.exact"


def test_dir_lists_the_lazy_names():
    names = dir(mmshbm)
    assert {"backbone", "Branch", "default_beam", "exact", "studies"} <= set(names)
    assert names == sorted(names)


#: 0.2 method module -> a public class it defined (the methods stood side by side in 0.2)
METHOD_PATHS_02 = {
    "mmshbm.methods.mms_hbm": ("mmshbm.methods.mms.conservative", "MMSHBMProblem"),
    "mmshbm.methods.forced": ("mmshbm.methods.mms.forced", "ForcedResponseProblem"),
    "mmshbm.methods.epmc": ("mmshbm.methods.mms.epmc", "EPMCProblem"),
    "mmshbm.methods.penalty_hbm": ("mmshbm.methods.penalty.hbm", "PenaltyHBMProblem"),
    "mmshbm.methods.penalty_forced": ("mmshbm.methods.penalty.forced", "PenaltyForcedProblem"),
    "mmshbm.methods.shooting": ("mmshbm.methods.shooting.conservative", "ShootingProblem"),
    "mmshbm.methods.shooting_forced": ("mmshbm.methods.shooting.forced", "ShootingForcedProblem"),
    "mmshbm.methods.friction_forced": ("mmshbm.methods.mms.friction_forced", "FrictionForcedProblem"),
    "mmshbm.methods.friction_penalty": ("mmshbm.methods.penalty.jenkins", "JenkinsForcedProblem"),
}


@pytest.mark.parametrize("old", sorted(METHOD_PATHS_02))
def test_method_paths_of_0_2_give_the_same_classes(old):
    new, name = METHOD_PATHS_02[old]
    assert getattr(importlib.import_module(old), name) is getattr(importlib.import_module(new), name)
