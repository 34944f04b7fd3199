"""``python -m mmshbm``: the command line."""

from .cli import main

raise SystemExit(main())
