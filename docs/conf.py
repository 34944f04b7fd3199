"""Sphinx configuration of the mmshbm documentation: the API reference from the
docstrings, the notes in docs/*.md (MyST), and a gallery of the scripts in examples/.

Build (warnings are errors, as in CI)::

    pip install '.[docs]' && python -m sphinx -W -b html docs docs/_build/html
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MPLBACKEND", "Agg")

import mmshbm  # noqa: E402

project = "mmshbm"
author = "The mmshbm developers"
copyright = "2026, The mmshbm developers"
version = release = mmshbm.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "sg_execution_times.rst", "**/README.txt"]
myst_heading_anchors = 3
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "show-inheritance": False}
html_theme = "alabaster"
html_static_path: list[str] = []
# cross-references to names that docstrings mention as plain words are not errors; the
# gallery's scraper is a function (no pickled environment cache for it)
nitpicky = False
suppress_warnings = ["ref.python", "config.cache"]


def _plain_math(app, what, name, obj, options, lines):
    """Docstrings write |x| for absolute values and ``ds *= a``: plain text, not reST
    substitutions or emphasis. Escape them outside literal blocks and inline literals.
    An indented block of equations after a line ending in a single colon is shown as a
    literal block (as ``::`` would)."""
    for i in range(len(lines) - 1):
        line = lines[i]
        rest = next((x for x in lines[i + 1:] if x.strip()), "")
        indent = len(line) - len(line.lstrip())
        opens = line.rstrip().endswith(":") and not line.rstrip().endswith("::")
        if (opens and not line.lstrip().startswith((":", "..")) and not lines[i + 1].strip()
                and len(rest) - len(rest.lstrip()) > indent):
            lines[i] = line.rstrip() + ":"
    literal = False
    for i, line in enumerate(lines):
        stripped = line.strip()
        if literal and stripped and not line.startswith((" ", "\t")):
            literal = False
        if not literal:
            parts = line.split("``")
            for j in range(0, len(parts), 2):  # outside inline literals
                parts[j] = parts[j].replace("|", "\\|").replace("*=", "\\*=")
            lines[i] = "``".join(parts)
        if stripped.endswith("::"):
            literal = True


def setup(app):
    app.connect("autodoc-process-docstring", _plain_math)


# ---------------------------------------------------------------------- gallery
def _png_scraper(block, block_vars, gallery_conf):
    """Collect the PNG files an example wrote (the package draws on Figure objects, not
    pyplot, and every example writes its figure itself)."""
    from sphinx_gallery.scrapers import figure_rst

    out_dir = Path(block_vars["src_file"]).parent / "out"
    seen = gallery_conf.setdefault("_seen_pngs", set())
    new = sorted(p for p in out_dir.glob("*.png")
                 if p not in seen and p.stat().st_mtime >= _png_scraper.start)
    images = []
    for png, target in zip(new, block_vars["image_path_iterator"], strict=False):
        shutil.copyfile(png, target)
        seen.add(png)
        images.append(target)
    return figure_rst(images, gallery_conf["src_dir"])


_png_scraper.start = 0.0


def _reset(gallery_conf, fname, when=None):
    import time

    _png_scraper.start = time.time() - 1.0


sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "image_scrapers": (_png_scraper,),
    "reset_modules": (_reset,),
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
}
