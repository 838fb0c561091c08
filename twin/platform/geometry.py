"""Platform geometry read from the compiled MJCF: the one source of truth.

:class:`Geometry` holds what the kinematics need, in the thesis frames (x forward, y right,
z down): gimbal positions (Tables B.2, B.4), the UGP at neutral, and each leg's stroke.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import mujoco
import numpy as np
from numpy.typing import NDArray

from twin.core.errors import ModelFileError
from twin.core.frames import MJ_FROM_THESIS, MJ_FROM_THESIS_QUAT
from twin.platform.facts import load_model

N_LEGS = 6


@dataclass(frozen=True, eq=False)
class Geometry:
    """Kinematic description of a six-legged Stewart platform.

    Attributes
    ----------
    name : str
        Model name.
    base_gimbals : ndarray, shape (6, 3)
        Base gimbal positions b_j in the base frame F^b [m].
    cabin_gimbals : ndarray, shape (6, 3)
        Cabin gimbal positions a_j in the cabin frame F^c [m].
    neutral_ugp : ndarray, shape (3,)
        UGP position c^b at the neutral pose [m] (z down, so its z is minus the height).
    leg_min, leg_max : ndarray, shape (6,)
        Shortest and longest leg length the stroke allows [m].

    """

    name: str
    base_gimbals: NDArray[np.float64]
    cabin_gimbals: NDArray[np.float64]
    neutral_ugp: NDArray[np.float64]
    leg_min: NDArray[np.float64]
    leg_max: NDArray[np.float64]

    @property
    def neutral_height(self) -> float:
        """Height of the UGP above the base plane at neutral [m]."""
        return float(-self.neutral_ugp[2])

    @property
    def neutral_lengths(self) -> NDArray[np.float64]:
        """Leg lengths at the neutral pose [m] (Eq A.5-A.6 at zero offsets)."""
        return np.linalg.norm(self.neutral_ugp + self.cabin_gimbals - self.base_gimbals, axis=1)

    @property
    def stroke(self) -> NDArray[np.float64]:
        """Actuator stroke of each leg [m]."""
        return self.leg_max - self.leg_min


def _site_pos(model: mujoco.MjModel, name: str, body: str) -> NDArray[np.float64]:
    try:
        site = model.site(name)
    except KeyError:
        raise ModelFileError(f"platform model has no site '{name}'") from None
    if model.site_bodyid[site.id] != model.body(body).id:
        raise ModelFileError(f"site '{name}' must belong to body '{body}'")
    return np.array(model.site_pos[site.id], dtype=float)


def geometry_from_model(model: mujoco.MjModel, name: str = "") -> Geometry:
    """Read the geometry of a compiled platform model.

    The model must follow the twin's conventions (see :mod:`twin.platform.build`): bodies
    ``base`` (at the world origin) and ``cabin``, both in thesis orientation; sites
    ``base_gimbal_j`` and ``cabin_gimbal_j``; slide joints ``leg j`` whose range is the stroke.

    Parameters
    ----------
    model : mujoco.MjModel
        A compiled platform model.
    name : str
        A label for the geometry.

    Returns
    -------
    Geometry

    Raises
    ------
    ModelFileError
        If the model lacks a body, site or joint the twin needs, or its frames differ.

    """
    for body in ("base", "cabin"):
        try:
            model.body(body)
        except KeyError:
            raise ModelFileError(f"platform model has no body '{body}'") from None
    base_id, cabin_id = model.body("base").id, model.body("cabin").id
    for bid in (base_id, cabin_id):
        if not np.allclose(model.body_quat[bid], MJ_FROM_THESIS_QUAT):
            raise ModelFileError("base and cabin bodies must carry the thesis frame (quat 0 1 0 0)")
    if not np.allclose(model.body_pos[base_id], 0.0):
        raise ModelFileError("the base body must sit at the world origin")
    base = np.array([_site_pos(model, f"base_gimbal_{j + 1}", "base") for j in range(N_LEGS)])
    cabin = np.array([_site_pos(model, f"cabin_gimbal_{j + 1}", "cabin") for j in range(N_LEGS)])
    ugp = MJ_FROM_THESIS @ model.body_pos[cabin_id] + _site_pos(model, "ugp", "cabin")
    ranges = []
    for j in range(N_LEGS):
        try:
            jid = model.joint(f"leg{j + 1}").id
        except KeyError:
            raise ModelFileError(f"platform model has no slide joint 'leg{j + 1}'") from None
        if not model.jnt_limited[jid]:
            raise ModelFileError(f"joint 'leg{j + 1}' must be limited: its range is the stroke")
        ranges.append(model.jnt_range[jid])
    ranges = np.array(ranges, dtype=float)
    return Geometry(
        name=name,
        base_gimbals=base,
        cabin_gimbals=cabin,
        neutral_ugp=ugp,
        leg_min=ranges[:, 0].copy(),
        leg_max=ranges[:, 1].copy(),
    )


@cache
def load_geometry(platform: str) -> Geometry:
    """Return the geometry of a named platform, read from its compiled MJCF.

    Parameters
    ----------
    platform : str
        ``"mpi"`` or ``"srs"``.

    Examples
    --------
    >>> geo = load_geometry("mpi")
    >>> round(geo.neutral_height, 3)
    1.209

    """
    return geometry_from_model(load_model(platform), name=platform)
