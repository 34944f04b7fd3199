"""Where the test suite's files are, whatever folder of tests/ a test module sits in."""

from pathlib import Path

#: the tests/ folder (helpers such as roundoff.py, and data/)
TESTS = Path(__file__).resolve().parent
#: reference data of the tests
DATA = TESTS / "data"
#: the repository's root (README.md, docs/, pyproject.toml)
ROOT = TESTS.parent
#: the package's sources
PACKAGE = ROOT / "mmshbm"
