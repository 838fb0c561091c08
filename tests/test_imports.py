"""Every module of the package imports headless (no display, no MUJOCO_GL) and without warning."""

import os
import pkgutil
import subprocess
import sys
from pathlib import Path

import twin

ROOT = Path(__file__).parents[1]


def test_every_twin_module_imports_headless_without_warning():
    names = sorted(
        m.name
        for m in pkgutil.walk_packages(twin.__path__, "twin.")
        if not m.name.endswith(".__main__")  # ``python -m`` entry points run on import
    )
    assert len(names) > 50
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "MUJOCO_GL")}
    code = "import importlib, sys\nfor n in sys.argv[1:]:\n    importlib.import_module(n)\n"
    done = subprocess.run(
        [sys.executable, "-W", "error", "-c", code, *names],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
