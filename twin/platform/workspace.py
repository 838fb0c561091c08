"""Workspace tables (App. B.3) next to the thesis' Table 5.1, for the CLI and the demo."""

from __future__ import annotations

import numpy as np

from twin.core.thesis import table_5_1_targets
from twin.platform.kinematics import DofRange


def comparable(ws: dict[str, DofRange]) -> dict[str, float]:
    """Workspace figures in Table 5.1's form: spans [mm] and rotation limits [deg]."""
    out: dict[str, float] = {}
    for dof, r in ws.items():
        if r.rotational:
            out[f"{dof}_min"] = float(np.degrees(r.min))
            out[f"{dof}_max"] = float(np.degrees(r.max))
        else:
            out[dof] = r.span * 1000.0
    return out


def relative_errors(ws: dict[str, DofRange], platform: str) -> dict[str, float]:
    """Relative error of each Table 5.1 figure in magnitude, ``(|twin| - |thesis|) / |thesis|``.

    Negative means the twin reaches less far than the thesis states.
    """
    ours, ref = comparable(ws), table_5_1_targets(platform)
    return {k: (abs(ours[k]) - abs(ref[k])) / abs(ref[k]) for k in ref}


def to_json_dict(ws: dict[str, DofRange]) -> dict[str, dict[str, float | str | int]]:
    """Return the CLI JSON: per DOF ``min``, ``max``, ``unit`` (m or deg), limiting legs."""
    out: dict[str, dict[str, float | str | int]] = {}
    for dof, r in ws.items():
        scale = float(np.degrees(1.0)) if r.rotational else 1.0
        out[dof] = {
            "min": r.min * scale,
            "max": r.max * scale,
            "unit": "deg" if r.rotational else "m",
            "min_limited_by_leg": r.min_leg,
            "max_limited_by_leg": r.max_leg,
        }
    return out


def format_table(ws: dict[str, DofRange], platform: str, title: str = "") -> str:
    """Return a plain-text table of the workspace beside Table 5.1 (errors on magnitudes)."""
    ref = table_5_1_targets(platform)
    err = {k: v * 100 for k, v in relative_errors(ws, platform).items()}
    lines = [title or f"Workspace of '{platform}' (App. B.3) vs thesis Table 5.1"]
    lines.append(f"{'DOF':<7}{'min':>11}{'max':>12}{'range':>11}   {'Table 5.1':<16}error")
    for dof, r in ws.items():
        if r.rotational:
            lo, hi = ref[f"{dof}_min"], ref[f"{dof}_max"]
            lines.append(
                f"{dof:<7}{np.degrees(r.min):>10.2f}°{np.degrees(r.max):>+11.2f}°{'':>11}   "
                f"{f'{lo:+.1f}/{hi:+.1f}°':<16}"
                f"{err[dof + '_min']:+.2f}/{err[dof + '_max']:+.2f} %"
            )
        else:
            lines.append(
                f"{dof:<7}{r.min * 1000:>8.1f} mm{r.max * 1000:>+9.1f} mm"
                f"{r.span * 1000:>8.1f} mm   "
                f"{f'{ref[dof]:.0f} mm':<16}{err[dof]:+.2f} %"
            )
    return "\n".join(lines)
