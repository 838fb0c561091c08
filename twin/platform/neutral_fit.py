"""Fit a platform's neutral UGP height to its Table 5.1 workspace.

The thesis gives no neutral height for the SRS. With the stroke centred on each leg's neutral
length, the App. B.3 workspace depends on that height alone; this module finds the height whose
workspace best reproduces all Table 5.1 ranges (least squares on relative errors).

Run ``python -m twin.platform.neutral_fit srs`` to reproduce the value in ``build.toml``.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from twin.platform.build import BuildParameters, read_build_parameters
from twin.platform.facts import model_dir
from twin.platform.geometry import Geometry
from twin.platform.kinematics import workspace
from twin.platform.workspace import relative_errors


def geometry_at_height(p: BuildParameters, height: float) -> Geometry:
    """Return the geometry of ``p`` with the UGP ``height`` above the base, stroke centred."""
    ugp = np.array([0.0, 0.0, -height])
    neutral = np.linalg.norm(ugp + p.cabin_gimbals - p.base_gimbals, axis=1)
    return Geometry(
        name=f"{p.name}@{height:.4f}",
        base_gimbals=p.base_gimbals,
        cabin_gimbals=p.cabin_gimbals,
        neutral_ugp=ugp,
        leg_min=neutral - p.stroke / 2,
        leg_max=neutral + p.stroke / 2,
    )


@dataclass(frozen=True)
class HeightFit:
    """Result of :func:`fit_neutral_height`.

    Attributes
    ----------
    height : float
        Fitted neutral UGP height above the base plane [m].
    errors : dict
        Relative error of each Table 5.1 figure at that height.

    """

    height: float
    errors: dict[str, float]

    @property
    def worst(self) -> float:
        """Largest absolute relative error."""
        return max(abs(e) for e in self.errors.values())


def fit_neutral_height(
    p: BuildParameters, platform: str, bounds: tuple[float, float] = (0.5, 5.0)
) -> HeightFit:
    """Fit the neutral height of ``p`` to Table 5.1 of ``platform``.

    Parameters
    ----------
    p : BuildParameters
        Gimbals and stroke (its own neutral height is ignored).
    platform : str
        Which Table 5.1 column to fit (``"mpi"`` or ``"srs"``).
    bounds : tuple of float
        Search interval for the height [m].

    """

    def cost(h: float) -> float:
        errs = relative_errors(workspace(geometry_at_height(p, h)), platform)
        return float(np.sum(np.square(list(errs.values()))))

    coarse = np.linspace(*bounds, 46)
    best = coarse[int(np.argmin([cost(h) for h in coarse]))]
    step = coarse[1] - coarse[0]
    res = minimize_scalar(
        cost, bounds=(best - step, best + step), method="bounded", options={"xatol": 1e-6}
    )
    h = float(res.x)
    return HeightFit(h, relative_errors(workspace(geometry_at_height(p, h)), platform))


def main(argv: list[str] | None = None) -> int:
    """Print the fitted neutral height of a platform and the Table 5.1 errors it leaves."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("platform", choices=["mpi", "srs"])
    args = parser.parse_args(argv)
    params = read_build_parameters(model_dir(args.platform) / "build.toml")
    fit = fit_neutral_height(params, args.platform)
    print(f"fitted neutral height: {fit.height:.4f} m (build.toml has {params.neutral_height} m)")
    for key, err in fit.errors.items():
        print(f"  {key:<10} {err * 100:+.3f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
