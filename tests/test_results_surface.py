"""Every result object has the same surface: ``to_dict()`` (JSON-ready) and ``plot(path=...)``.

The instances are built directly from small synthetic data (the analyses themselves are tested
elsewhere); only the diagnosis runs for real, on one short reduced-model run.
"""

from __future__ import annotations

import json
import os

os.environ.setdefault("MPLBACKEND", "Agg")

import numpy as np
import pytest

from twin.agard.compare import Comparison, DofResponse, PlatformDynamics
from twin.agard.df import DfResult
from twin.agard.noise_level import NoiseLevelPoint, NoiseLevelResult, decompose
from twin.agard.omct import OmctResult
from twin.agard.snr import SnrResult
from twin.agard.threshold import LagDelayStepFit, ThresholdResult
from twin.chain.config import motion_system
from twin.core.errors import UsageError
from twin.measurement.describing_function import LagDelayFit
from twin.pilot.identification.arx import ArxOrders
from twin.pilot.identification.mle import PilotFit
from twin.pilot.models.pitch import PitchPilot
from twin.pilot.studies.experiment import ExperimentResult
from twin.pilot.studies.montecarlo import MonteCarloResult
from twin.platform.kinematics import ForwardResult

F = np.array([0.1, 0.3, 1.0, 3.0])
H = np.exp(-2j * np.pi * F * 0.05) / (1 + 2j * np.pi * F * 0.02)


def _point() -> NoiseLevelPoint:
    t = np.arange(0, 20, 0.01)
    y = np.sin(2 * np.pi * 0.5 * t) + 0.01 * np.random.default_rng(0).standard_normal(t.size)
    dec = decompose(t, y, 0.5, (4.0, 20.0))
    return NoiseLevelPoint("heave", 0.5, 0.1, dec, {"surge": (0.01, 0.03)}, "synthetic")


def _df() -> DfResult:
    return DfResult("pitch", F, H, {"roll": 0.01 * H}, H, 0.035, 0.05, "synthetic",
                    np.full(F.size, 1e-3), 0.05)  # fmt: skip


def _threshold() -> ThresholdResult:
    t = np.arange(0, 4, 0.01)
    cmd = 0.1 * (t >= 1)
    fit, analytic = LagDelayStepFit(0.05, 0.03, 1e-3), LagDelayStepFit(0.04, 0.02, 0.0)
    return ThresholdResult("heave", 0.1, 1.0, fit, analytic, 0.06, t, cmd, cmd, "synthetic")


def _dof_response() -> DofResponse:
    return DofResponse("pitch", F, H, H * 1.01, 0.01)


def _montecarlo() -> MonteCarloResult:
    rng = np.random.default_rng(1)
    runs = {k: H + 0.01 * rng.standard_normal((3, F.size)) for k in ("pe", "px")}
    std = {k: np.full(F.size, 0.01) for k in ("pe", "px")}
    return MonteCarloResult(F * 2 * np.pi, runs, runs, std, std, std, std,
                            {"pe": H, "px": H}, ArxOrders(2, 2, 2, 1, 1),
                            {"fc": [], "arx": []})  # fmt: skip


RESULTS = {
    "DfResult": _df,
    "NoiseLevelResult": lambda: NoiseLevelResult([_point()]),
    "SnrResult": lambda: SnrResult("heave", "srs", [_point()], source="synthetic"),
    "ThresholdResult": _threshold,
    "OmctResult": lambda: OmctResult("pitch", F * 2 * np.pi, H, H, "synthetic", "srs"),
    "Comparison": lambda: Comparison(
        motion_system("srs"), {"pitch": _dof_response()}, {"pitch": H}
    ),
    "PlatformDynamics": lambda: PlatformDynamics(
        "mpi", {"pitch": _dof_response()}, {"pitch": LagDelayFit(0.02, 0.05, 0.0)}
    ),
    "ExperimentResult": lambda: ExperimentResult(
        {1: {"var_e": 1.0, "crossover_d": 2.0}, 2: {"var_e": 1.5, "crossover_d": 1.8}},
        {"delay": {"var_e": 0.5}},
    ),
    "MonteCarloResult": _montecarlo,
    "ForwardResult": lambda: ForwardResult(np.zeros((3, 6)), 2, np.array([2, 1, 1]), 1e-9),
    "PilotFit": lambda: PilotFit(PitchPilot(), {"k_v": 0.1, "tau_v": 0.01}, 85.0, 0.02),
}


def _check_surface(result, tmp_path) -> None:
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    json.dumps(result.to_dict())
    png = tmp_path / "result.png"
    fig = result.plot(path=str(png))
    assert isinstance(fig, Figure) and fig.axes
    assert any(ax.get_xlabel() for ax in fig.axes)
    assert any(ax.get_ylabel() for ax in fig.axes)
    assert png.stat().st_size > 0
    plt.close(fig)


@pytest.mark.parametrize("name", sorted(RESULTS))
def test_result_has_to_dict_and_plot(name, tmp_path):
    _check_surface(RESULTS[name](), tmp_path)


@pytest.fixture(scope="module")
def diagnosis(tmp_path_factory):
    from twin.diagnose.diagnosis import diagnose
    from twin.diagnose.hidden import record_runs

    mpi = motion_system("mpi")
    runs = record_runs(mpi, mpi, "heave", tmp_path_factory.mktemp("diag"), 5, signals=(2,))
    return diagnose(runs, seed=1)


def test_diagnosis_has_to_dict_and_plot(diagnosis, tmp_path):
    _check_surface(diagnosis, tmp_path)
    assert json.loads(json.dumps(diagnosis.to_dict())) == diagnosis.to_dict()


def test_diagnosis_plot_of_a_dof_not_analysed_is_an_error(diagnosis):
    with pytest.raises(UsageError, match="'roll' was not analysed; analysed: heave"):
        diagnosis.plot(dof="roll")
