"""The documentation builds without a warning (``make docs`` builds it with ``-W``).

The quick build (``TWIN_DOCS_QUICK=1``): every page, the API reference from the docstrings
(numpydoc), the CLI from the argument parser and the schemas, but no figures generated (a
missing figure is a note) and the notebooks rendered as stored. The figures themselves are
made by ``docs/figures.py`` with the commands the pages show; the tests of those commands
are elsewhere.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("docs")
    env = {**os.environ, "TWIN_DOCS_QUICK": "1", "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
           "-d", str(out / "doctrees"), str(DOCS), str(out / "html")]  # fmt: skip
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    return done, out / "html"


def test_the_docs_build_without_warnings(built):
    done, _ = built
    assert done.returncode == 0, done.stderr[-5000:]
    assert done.stderr.strip() == "", done.stderr[-5000:]


def test_every_page_the_brief_asks_for_is_there(built):
    _, html = built
    pages = ["index", "getting-started", "conventions", "limitations", "design-decisions",
             "references", "notebooks", "reference/cli", "reference/api", "reference/formats",
             "reference/reliability", "validation/index"]  # fmt: skip
    pages += [f"guides/{g}" for g in ("configurations", "agard", "pilots", "diagnose", "import",
                                       "studies", "recordings", "full-model")]  # fmt: skip
    pages += [f"notebooks/{p.stem}" for p in (ROOT / "notebooks").glob("*.ipynb")]
    missing = [p for p in pages if not (html / f"{p}.html").is_file()]
    assert missing == []
    cli = (html / "reference" / "cli.html").read_text()
    for command in ("workspace", "simulate", "compare", "dynamics", "agard", "pilot", "diagnose",
                    "design", "import", "sweep"):  # fmt: skip
        assert f'id="twin-{command}"' in cli, command
    api = (html / "reference" / "api.html").read_text()
    assert "twin.chain.simulate" in api and "twin.diagnose.diagnosis" in api


def test_every_figure_the_pages_name_is_made_by_figures_py():
    sys.path.insert(0, str(DOCS))
    try:
        import figures
    finally:
        sys.path.remove(str(DOCS))
    made = {f for _, files in figures.FIGURES.values() for f in files}
    named = set()
    for page in DOCS.rglob("*.md"):
        if "_build" in page.parts or "_figures" in page.parts:
            continue
        named |= set(re.findall(r"\{twinfigure\}\s+(\S+)", page.read_text()))
    assert named <= made, sorted(named - made)
    assert made <= named, f"made but shown nowhere: {sorted(made - named)}"
