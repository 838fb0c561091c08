"""The platform's look, read from its MJCF: the base's and the cabin's visual geoms and sites.

Recordings and figures draw the platform from the model itself, not from a hand-made outline:
each visual geom of the ``base`` and ``cabin`` bodies as a box, cylinder or capsule in its
body's frame (thesis coordinates, since both bodies carry the thesis-from-MuJoCo rotation,
:data:`twin.core.frames.MJ_FROM_THESIS_QUAT`), its colour from its material, and the cabin's IMU
site.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import mujoco
import numpy as np
from numpy.typing import NDArray

from twin.platform.facts import PLATFORMS, load_model

FloatArray = NDArray[np.float64]
#: The bodies drawn (the legs are drawn between their gimbals, as they move).
BODIES = ("base", "cabin")
_KINDS = {
    int(mujoco.mjtGeom.mjGEOM_BOX): "box",
    int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder",
    int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule",
}


@dataclass(frozen=True)
class Shape:
    """One visual geom in its body's frame.

    Attributes
    ----------
    name : str
        The geom's name in the MJCF.
    body : str
        ``"base"`` or ``"cabin"``.
    kind : str
        ``"box"``, ``"cylinder"`` or ``"capsule"``.
    size : tuple of float
        Box: half sizes (x, y, z) [m]; cylinder and capsule: (radius, half length along the
        geom's z) [m], as MuJoCo's.
    pos : tuple of float
        Centre in the body frame [m].
    quat_xyzw : tuple of float
        Orientation in the body frame (scalar last).
    rgba : tuple of float
        Colour, 0-1.

    """

    name: str
    body: str
    kind: str
    size: tuple[float, ...]
    pos: tuple[float, float, float]
    quat_xyzw: tuple[float, float, float, float]
    rgba: tuple[float, float, float, float]


@cache
def platform_shapes(platform: str) -> tuple[Shape, ...]:
    """Return the base's and cabin's visual geoms of a named platform (``mpi`` or ``srs``).

    Raises
    ------
    KeyError
        For a platform name that is not one of :data:`twin.platform.facts.PLATFORMS`.

    """
    if platform not in PLATFORMS:
        raise KeyError(f"unknown platform {platform!r}; known: {', '.join(PLATFORMS)}")
    model = load_model(platform)
    out = []
    for g in range(model.ngeom):
        body = model.body(int(model.geom_bodyid[g])).name
        kind = _KINDS.get(int(model.geom_type[g]))
        if body not in BODIES or kind is None:
            continue
        mat = int(model.geom_matid[g])
        rgba = model.mat_rgba[mat] if mat >= 0 else model.geom_rgba[g]
        size = model.geom_size[g][: 3 if kind == "box" else 2]
        w, x, y, z = model.geom_quat[g]
        out.append(Shape(model.geom(g).name or f"geom{g}", body, kind,
                         tuple(map(float, size)), tuple(map(float, model.geom_pos[g])),
                         (float(x), float(y), float(z), float(w)),
                         tuple(map(float, rgba))))  # fmt: skip
    return tuple(out)


def imu_site(platform: str) -> FloatArray:
    """Return the model's IMU site in the cabin frame [m] (thesis coordinates)."""
    model = load_model(platform)
    return np.array(model.site("imu").pos, dtype=float)
