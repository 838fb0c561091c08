"""Test set-up for tests/ and the docstring examples of twin/ (this is the rootdir conftest).

No display and no OpenGL backend are needed by the suite. Under pytest-xdist every worker
keeps OpenBLAS to one thread: two workers on two cores with a BLAS pool each would
oversubscribe the machine (both are set here, before anything imports numpy or dm_control).
"""

import os
import sys

# dm_control picks an OpenGL backend at import; the suite renders nothing, so switch it off
# (an empty MUJOCO_GL would make the import fail).
if not os.environ.get("MUJOCO_GL"):
    os.environ["MUJOCO_GL"] = "disable"

if os.environ.get("PYTEST_XDIST_WORKER") and "numpy" not in sys.modules:
    for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_name, "1")
