"""Test set-up: no display and no OpenGL backend are needed by the suite."""

import os

# dm_control picks an OpenGL backend at import; the suite renders nothing, so switch it off
# (an empty MUJOCO_GL would make the import fail).
if not os.environ.get("MUJOCO_GL"):
    os.environ["MUJOCO_GL"] = "disable"
