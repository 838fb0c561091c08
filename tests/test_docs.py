"""The documentation builds without a warning (``make docs`` builds it with ``-W``).

The quick build (``TWIN_DOCS_QUICK=1``): every page, the CLI from the argument parser and the
schemas, no figure generated (a missing figure is a note) and the notebooks rendered as
stored. The normal suite leaves out the API reference (``TWIN_DOCS_API=0``: the autodoc of
every module takes about a minute); ``make test-all`` builds it too, and so checks every
docstring numpydoc and docutils read. The figures are made by ``docs/figures.py`` with the
commands the pages show; the tests of those commands are elsewhere.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def build(out: Path, api: bool) -> tuple[subprocess.CompletedProcess, Path]:
    """Build the docs quickly into ``out``; return the finished process and the HTML folder."""
    env = {**os.environ, "TWIN_DOCS_QUICK": "1", "TWIN_DOCS_API": "1" if api else "0",
           "PYTHONPATH": str(ROOT)}  # fmt: skip
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
           "-d", str(out / "doctrees"), str(DOCS), str(out / "html")]  # fmt: skip
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900)
    return done, out / "html"


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    return build(tmp_path_factory.mktemp("docs"), api=False)


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


@pytest.mark.slow
def test_the_docs_build_with_the_api_reference_without_warnings(tmp_path):
    done, html = build(tmp_path, api=True)
    assert done.returncode == 0, done.stderr[-5000:]
    assert done.stderr.strip() == "", done.stderr[-5000:]
    api = (html / "reference" / "api.html").read_text()
    for module in ("twin.chain.simulate", "twin.diagnose.diagnosis", "twin.cli.main"):
        assert module in api, module
        assert (html / "reference" / "generated" / f"{module}.html").is_file()


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
