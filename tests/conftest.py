"""Fixtures of the models that test modules in several folders share (shared_models.py).
Each is built once per test module, as the modules' own fixtures were."""

import os

import pytest
from shared_models import default_beam, nlvib_cantilever


@pytest.hookimpl(tryfirst=True)
def pytest_cmdline_main(config):
    """Spread the test files over the machine's cores where pytest-xdist is installed (it is in
    the ``test`` extra) and the command line does not choose (``-n 0`` runs in one process).
    Whole files go to one worker (``loadfile``), so a module-scoped fixture is built once.
    One test file named alone runs in one process (starting workers would cost more)."""
    if not config.pluginmanager.hasplugin("xdist") or "PYTEST_XDIST_WORKER" in os.environ:
        return
    if len(config.args) == 1 and config.args[0].split("::")[0].endswith(".py"):
        return
    if config.option.numprocesses is None and not config.getoption("usepdb", False):
        config.option.numprocesses = "auto"
        if config.option.dist == "no":
            config.option.dist = "loadfile"


@pytest.fixture(scope="module")
def beam21():
    """The default beam, 21 elements."""
    return default_beam(21)


@pytest.fixture(scope="module")
def beam8():
    """The default beam, 8 elements."""
    return default_beam(8)


@pytest.fixture(scope="module")
def full_mass():
    """NLvib's cantilever, 21 elements, full mass matrix."""
    return nlvib_cantilever(21)
