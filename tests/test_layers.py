"""The rooms' import contract (pyproject.toml, [tool.importlinter]) holds and catches a breach.

``lint-imports`` runs on a copy of the package (first on PYTHONPATH, so grimp reads the copy,
not the installed package) with the repository's configuration: kept on the copy as it is,
broken once a low room imports a high one.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
LINT_IMPORTS = Path(sys.executable).with_name("lint-imports")
#: Imports that go up, appended to a copy: (module file, the import, the edge lint-imports names).
BREACHES = (
    ("core/errors.py", "import twin.cli", "twin.core.errors -> twin.cli"),
    (
        "agard/df.py",
        "import twin.pilot.models.forcing",
        "twin.agard.df -> twin.pilot.models.forcing",
    ),
    (
        "pilot/models/forcing.py",
        "from twin.pilot.studies import population",
        "twin.pilot.models.forcing -> twin.pilot.studies.population",
    ),
)


@pytest.fixture
def package(tmp_path: Path) -> Path:
    """Return a folder holding a copy of ``twin/`` (without caches)."""
    shutil.copytree(ROOT / "twin", tmp_path / "twin", ignore=shutil.ignore_patterns("__pycache__"))
    return tmp_path


def lint(package: Path) -> subprocess.CompletedProcess:
    """Run ``lint-imports`` on the copy in ``package`` with the repository's contracts."""
    path = os.pathsep.join([str(package), os.environ.get("PYTHONPATH", "")])
    return subprocess.run(
        [str(LINT_IMPORTS), "--no-cache", str(ROOT / "pyproject.toml")],
        cwd=package,
        env={**os.environ, "PYTHONPATH": path},
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_the_package_keeps_its_rooms(package):
    done = lint(package)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "Contracts: 2 kept, 0 broken." in done.stdout


def test_an_import_up_a_room_breaks_the_contract_naming_it(package):
    for module, line, _ in BREACHES:
        with open(package / "twin" / module, "a", encoding="utf-8") as fh:
            fh.write(f"\n{line}  # a breach\n")
    done = lint(package)
    assert done.returncode != 0
    assert "Contracts: 0 kept, 2 broken." in done.stdout, done.stdout
    for _, _, edge in BREACHES:
        assert edge in done.stdout, (edge, done.stdout)
