"""Reference numbers printed in the thesis (Nieuwenhuizen 2012), for reports and tests.

Only numbers read from the thesis' tables live here; nothing in this module is computed.
"""

from __future__ import annotations

from types import MappingProxyType

#: Table 5.1 (= Tables B.1, B.3): workspace per DOF. Translations are total ranges [mm];
#: rotations are (min, max) [deg] about neutral.
TABLE_5_1 = MappingProxyType(
    {
        "mpi": MappingProxyType(
            {
                "surge": 922.0,
                "sway": 848.0,
                "heave": 500.0,
                "roll": (-26.6, 26.6),
                "pitch": (-25.1, 24.1),
                "yaw": (-43.5, 43.5),
            }
        ),
        "srs": MappingProxyType(
            {
                "surge": 2240.0,
                "sway": 2062.0,
                "heave": 1314.0,
                "roll": (-25.9, 25.9),
                "pitch": (-23.7, 24.3),
                "yaw": (-41.6, 41.6),
            }
        ),
    }
)


def table_5_1_targets(platform: str) -> dict[str, float]:
    """Table 5.1 as flat comparable figures: spans [mm] and rotation limits [deg].

    Keys are ``surge, sway, heave`` (total range, mm) and ``roll_min, roll_max, pitch_min,
    pitch_max, yaw_min, yaw_max`` (deg).
    """
    table = TABLE_5_1[platform]
    out: dict[str, float] = {}
    for dof, value in table.items():
        if isinstance(value, tuple):
            out[f"{dof}_min"], out[f"{dof}_max"] = value
        else:
            out[dof] = value
    return out
