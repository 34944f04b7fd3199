"""Fixtures of the models that test modules in several folders share (shared_models.py).
Each is built once per test module, as the modules' own fixtures were."""

import pytest
from shared_models import default_beam, nlvib_cantilever


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
