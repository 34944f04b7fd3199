"""``python -m mmshbm``: the command line."""

from .cli import console

raise SystemExit(console())
