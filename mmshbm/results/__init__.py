"""What the methods produce: :class:`~mmshbm.results.branch.Branch` (a backbone) and
:class:`~mmshbm.results.response.FrequencyResponse` (a forced response), both
:class:`~mmshbm.results.base.ResultBase`, and their file format."""

import importlib

# public names of the flat ``mmshbm.results`` module of 0.1 -> the module that holds them now
_NAMES = {
    "Branch": "branch", "versions": "base", "branch_payload": "branch",
    "branch_from_payload": "branch", "rebuild_model": "models",
    "write_archive": "archive", "read_archive": "archive",
    "FrequencyResponse": "response", "ResultBase": "base", "TruncationEstimate": "truncation",
}


def __getattr__(name: str):
    if name in _NAMES:
        return getattr(importlib.import_module(f"{__name__}.{_NAMES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_NAMES))
