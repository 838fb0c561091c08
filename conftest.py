"""Test set-up for tests/ and the docstring examples of twin/ (this is the rootdir conftest).

No display and no OpenGL backend are needed by the suite. Under pytest-xdist every worker
keeps OpenBLAS to one thread: two workers on two cores with a BLAS pool each would
oversubscribe the machine (both are set here, before anything imports numpy or dm_control).
``--dist loadfile`` hands whole files to the workers in collection order, so the longest
files are collected first (a long file started last leaves the other worker idle).
"""

import os
import sys

import pytest

# dm_control picks an OpenGL backend at import; the suite renders nothing, so switch it off
# (an empty MUJOCO_GL would make the import fail).
if not os.environ.get("MUJOCO_GL"):
    os.environ["MUJOCO_GL"] = "disable"

if os.environ.get("PYTEST_XDIST_WORKER") and "numpy" not in sys.modules:
    from twin.core.threads import single_blas_thread

    single_blas_thread()

#: Files taking longest in the fast suite (seconds measured on the 2-core machine, rounded).
LONGEST_FIRST = (
    "test_tasks.py",  # 45: a two-process Dask cluster
    "test_diagnose.py",  # 30
    "test_diagnose_hidden.py",  # 25
    "test_fuzz_inputs.py",  # 15
    "test_interrupts.py",  # 15: Ctrl-C to commands at work (a local cluster, MuJoCo threads)
    "test_pilot_chapter6.py",  # 20
    "test_agard_reproductions.py",  # 15
    "test_pilot_chapter2.py",  # 15
)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Put the items of :data:`LONGEST_FIRST` first (stable: the rest keep their order)."""
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))
