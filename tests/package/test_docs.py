"""The documentation's tutorial runs as written (its ``>>>`` lines are doctests), and its
installation page states the Python the package requires."""

import doctest
import re

import pytest
from locations import ROOT

DOCS = ROOT / "docs"


@pytest.mark.parametrize("name", ["tutorial.md"])
def test_doc_page_runs_as_doctest(name):
    path = DOCS / name
    test = doctest.DocTestParser().get_doctest(path.read_text(), {}, name, str(path), 0)
    assert len(test.examples) > 20
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    runner.run(test)
    assert runner.failures == 0, f"{runner.failures} of {len(test.examples)} examples of {name} failed"


def test_installation_page_states_the_python_of_pyproject():
    required = re.search(r'requires-python = ">=(\d+\.\d+)"',
                         (DOCS.parent / "pyproject.toml").read_text()).group(1)
    text = (DOCS / "installation.md").read_text()
    assert f"Python ≥ {required}" in text and "pip install ." in text
    index = (DOCS / "index.rst").read_text()
    assert "installation" in index and "tutorial" in index


@pytest.mark.slow
def test_api_pages_show_no_raw_roles(tmp_path):
    """Build the HTML docs (without running the gallery): no warning, and no role left as
    text (``:attr:`x``` shown literally where reST did not read it as a role)."""
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_parser")
    pytest.importorskip("sphinx_gallery")
    import html
    import subprocess
    import sys

    out = tmp_path / "html"
    run = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", "-D", "plot_gallery=0",
                          str(DOCS), str(out)], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    raw = []
    for page in sorted((out / "api").glob("*.html")):
        text = html.unescape(re.sub(r"<[^>]+>", "", page.read_text()))
        raw += [f"{page.name}: {m.group(0)}"
                for m in re.finditer(r":(attr|meth|class|func|mod|data):`[^`]*`", text)]
    assert raw == []
