"""The ``twin`` namespace, the result protocol, units and plotting without a backend.

- the entry points of :mod:`twin` work on the cheap path (reduced model, short signals) and take
  a configuration as a name, a ``twin-config/1`` file or a ``MotionSystem`` with the same result;
  everything after their obvious arguments is keyword-only;
- every class of the package with ``to_dict`` or ``plot`` is a :class:`twin.core.results.Result`
  (frequency responses a :class:`~twin.core.results.FrequencyResult` too) or is named below as a
  part or a setting, with the reason; the instances of ``test_results_surface`` are checked
  end to end (``to_frame``, ``plot`` on given axes, ``to_frd`` in rad/s);
- a method named as python-control's is not ours: ``response_at_hz`` at ``f`` equals
  python-control's system at ``s = 2j pi f``;
- importing the twin and plotting leaves matplotlib's backend and pyplot alone.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import json
import subprocess
import sys
from pathlib import Path

import control as ct
import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

import twin
from twin.chain.trajectory import Trajectory
from twin.core.errors import UnknownPlatformError, UsageError
from twin.core.results import FrequencyResult, Result

ROOT = Path(__file__).parents[1]


def _heave(seconds: float = 3.0) -> Trajectory:
    t = np.arange(round(seconds * 100) + 1) / 100
    v = np.zeros((t.size, 6))
    v[:, 2] = 0.01 * np.sin(2 * np.pi * 0.5 * t) * np.clip(t, 0, 1)
    return Trajectory(100.0, v)


# --- the namespace ---------------------------------------------------------------------------


def test_all_names_exist_and_the_entry_points_are_documented():
    for name in twin.__all__:
        assert hasattr(twin, name), name
    for name in ("configure", "simulate", "describing_function", "agard_test", "session",
                 "compare", "diagnose_runs", "load_run", "workspace", "fly"):  # fmt: skip
        fn = getattr(twin, name)
        assert name in twin.__all__ and fn.__doc__, name


#: The positional arguments of each entry point; the rest must be keyword-only.
POSITIONAL = {
    "configure": ["config"],
    "simulate": ["config", "signal"],
    "describing_function": ["config", "dof"],
    "agard_test": ["config", "test", "dof"],
    "session": ["config"],
    "compare": ["config"],
    "diagnose_runs": ["runs"],
    "load_run": ["path"],
    "workspace": ["platform"],
    "fly": ["config"],
}


@pytest.mark.parametrize("name", sorted(POSITIONAL))
def test_only_the_obvious_arguments_are_positional(name):
    params = inspect.signature(getattr(twin, name)).parameters.values()
    positional = [p.name for p in params if p.kind is p.POSITIONAL_OR_KEYWORD]
    assert positional == POSITIONAL[name]
    assert all(p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY, p.VAR_KEYWORD) for p in params)


def test_the_namespace_s_defaults_are_those_of_the_functions_it_calls():
    from twin.agard.compare import compare
    from twin.core.frames import DOF_NAMES
    from twin.diagnose.diagnosis import diagnose

    ours, theirs = (
        inspect.signature(twin.diagnose_runs).parameters,
        inspect.signature(diagnose).parameters,
    )
    for name in ("model", "max_hz", "realisations", "seed", "physics", "imu_noise"):
        assert ours[name].default == theirs[name].default, name
    assert inspect.signature(twin.compare).parameters["dofs"].default == DOF_NAMES
    assert inspect.signature(compare).parameters["signals"].default == (1, 2, 3)
    assert set(twin.AGARD_TESTS) == {"df", "noise", "snr", "threshold", "omct", "linearity",
                                     "hysteresis", "bump", "limits", "parasitic"}  # fmt: skip


def test_keyword_only_arguments_are_refused_by_position():
    with pytest.raises(TypeError, match="positional"):
        twin.simulate("mpi", _heave(), "full")  # type: ignore[misc]
    with pytest.raises(TypeError, match="positional"):
        twin.describing_function("mpi", "pitch", "reduced")  # type: ignore[misc]
    with pytest.raises(TypeError, match="positional"):
        twin.configure("mpi", 5.0)  # type: ignore[misc]


def _three_ways(tmp_path):
    """The same configuration as a name, a twin-config/1 path (str and Path) and an object."""
    obj = twin.configure("mpi")
    path = obj.save(tmp_path / "mpi.json")
    return ["mpi", str(path), path, obj]


def test_a_name_a_file_and_an_object_simulate_alike(tmp_path):
    runs = [twin.simulate(c, _heave(), seed=3) for c in _three_ways(tmp_path)]
    for other in runs[1:]:
        assert np.array_equal(other.imu.accel, runs[0].imu.accel)
        assert np.array_equal(other.response.pose, runs[0].response.pose)
    assert runs[0].response.pose[:, 2].std() > 1e-3  # it moved


def test_a_name_a_file_and_an_object_give_the_same_describing_function(tmp_path):
    results = [twin.describing_function(c, "pitch", signals=(2,), seed=1)
               for c in _three_ways(tmp_path)]  # fmt: skip
    for other in results[1:]:
        assert np.array_equal(other.response, results[0].response)
    r = results[0]
    assert abs(r.delay_s - 0.035) < 0.005  # the MPI's 35 ms, fitted
    assert isinstance(r, FrequencyResult)


def test_simulate_takes_a_builtin_signal_by_name_and_defaults_to_the_reduced_model():
    sim = twin.simulate("srs", "rest-1")
    assert sim.imu.accel.shape[1] == 3 and sim.response.pose.shape[1] == 6
    with pytest.raises(UsageError, match="signal: expected a Trajectory"):
        twin.simulate("srs", 3)  # type: ignore[arg-type]


def test_a_bad_configuration_is_named_with_what_is_allowed(tmp_path):
    with pytest.raises(UnknownPlatformError, match=r"unknown configuration 'mpii'.*condition-1"):
        twin.simulate("mpii", _heave())
    with pytest.raises(UsageError, match=r"config: expected a configuration name .* got int"):
        twin.workspace(3)  # type: ignore[arg-type]


def test_configure_overrides_what_it_is_given_on_any_form_of_configuration(tmp_path):
    for c in _three_ways(tmp_path):
        ms = twin.configure(c, break_hz=5, delay_ms=60)
        assert ms.filter_break_hz == 5.0 and ms.delay_s == pytest.approx(0.060)


def test_agard_test_runs_a_test_and_names_bad_tests_and_options():
    r = twin.agard_test("mpi", "threshold", "heave", amplitude=0.1875, step_s=0.5, seed=2)
    assert isinstance(r, Result) and r.dof == "heave"
    assert r.fit.t63_s == pytest.approx(r.analytic_fit.t63_s, rel=0.1)  # Eq 5.11's step
    with pytest.raises(UsageError, match="unknown AGARD test 'thresh'; expected one of df, "):
        twin.agard_test("mpi", "thresh", "heave")
    with pytest.raises(UsageError, match="takes no amplitudes; its options: amplitude, step_s"):
        twin.agard_test("mpi", "threshold", "heave", amplitudes=(0.1,))
    with pytest.raises(UsageError, match="the noise test drives one DOF"):
        twin.agard_test("mpi", "noise", ["heave", "pitch"])


def test_session_runs_several_tests_on_one_bench():
    from twin.agard.noise_level import run_noise

    with twin.session("mpi", seed=4) as s:
        noise = run_noise(s, "heave", amplitudes=(0.5,), window_s=4.0)
    assert s.count == 1 and isinstance(noise, Result)
    assert noise.to_frame()["amplitude"].tolist() == [pytest.approx(0.5, rel=1e-3)]


def test_workspace_takes_a_platform_or_any_configuration_of_it():
    from twin.platform.geometry import load_geometry
    from twin.platform.kinematics import workspace

    direct = workspace(load_geometry("srs"))
    for c in ("srs", "condition-3", twin.configure("condition-8")):
        ws = twin.workspace(c)
        assert {d: (r.min, r.max) for d, r in ws.items()} == {
            d: (r.min, r.max) for d, r in direct.items()
        }


def test_fly_flies_the_pitch_task_with_the_nominal_pilot_by_default():
    from twin.pilot.models.pitch import PitchPilot, simulate_pitch

    runs = twin.fly("condition-8", seed=1)
    same = simulate_pitch(PitchPilot(), "condition-8", seed=1)
    assert np.array_equal(runs.e, same.e) and runs.e.shape == (1, 8192)
    with pytest.raises(TypeError, match="positional"):
        twin.fly("condition-8", PitchPilot())  # type: ignore[misc]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    from twin.diagnose.hidden import record_runs

    mpi = twin.configure("mpi")
    return record_runs(mpi, mpi, "heave", tmp_path_factory.mktemp("api"), 5, signals=(2,))


def test_load_run_reads_a_run_folder(recorded):
    run = twin.load_run(recorded[0])
    assert run.imu.shape[1] == 6 and run.commands.values.shape[1] == 6


def test_diagnose_takes_the_runs_and_a_configuration_in_any_form(recorded, tmp_path):
    by_name = twin.diagnose_runs(recorded, config="mpi", seed=1, realisations=2)
    by_file = twin.diagnose_runs(recorded, config=_three_ways(tmp_path)[2], seed=1, realisations=2)
    assert by_name.to_dict()["findings"] == by_file.to_dict()["findings"] == []
    assert list(by_name.dofs) == ["heave"]
    assert by_name.to_frd().omega == pytest.approx(2 * np.pi * by_name.dofs["heave"].lines.f)
    with pytest.raises(UsageError, match="runs: expected a sequence of runs"):
        twin.diagnose_runs(recorded[0])
    with pytest.raises(TypeError, match="positional"):
        twin.diagnose_runs(recorded, "mpi")  # type: ignore[misc]
    # named apart from the subpackage: twin.diagnose stays the package once its modules load
    assert inspect.ismodule(twin.diagnose) and twin.diagnose.diagnosis.Diagnosis


# --- the result protocol ---------------------------------------------------------------------

#: Classes with ``to_dict`` that are not results of their own, and why.
NOT_RESULTS = {
    "twin.agard.bump.Reversal": "a row of BumpResult.to_frame()",
    "twin.agard.hysteresis.HysteresisLoop": "a row of HysteresisResult.to_frame()",
    "twin.agard.limits.DofLimits": "part of LimitsResult (its computed limits)",
    "twin.agard.limits.Reached": "part of LevelResult (the peaks reached)",
    "twin.agard.limits.LevelResult": "a row of LimitsResult.to_frame()",
    "twin.agard.noise_level.NoiseLevelPoint": "a row of NoiseLevelResult.to_frame()",
    "twin.agard.parasitic.Cell": "a row of ParasiticResult.to_frame()",
    "twin.agard.scheduled.RunReport": "a set of results (each a Result, each plotted)",
    "twin.pilot.studies.replication.EffectReplication": "a row of Replication.to_frame()",
    "twin.chain.limits.LimitReport": "part of a Simulation (limit counts)",
    "twin.ingest.importer.Clock": "part of ImportReport (a clock fit)",
    "twin.ingest.importer.ImportReport": "what twin import made of logs (text and JSON)",
    "twin.ingest.timebase.Regular": "part of ImportReport (a resampling)",
    "twin.pilot.models.adapt.Adapted": "a pilot (parameters), not a result",
    "twin.pilot.identification.felt_motion.MotionMatch": (
        "part of an identification (its motion chain)"
    ),
    "twin.pilot.studies.spread.Spread": "a setting (subjects' spreads)",
    "twin.platform.actuators.LegPhysics": "a setting (actuator physics)",
    "twin.platform.payload.Payload": "a setting (a payload)",
    "twin.platform.platform_physics.PlatformPhysics": "a setting (physics of a configuration)",
    "twin.core.tasks.outcome.Failure": "a failed task (an error report)",
}

#: Results that are frequency responses (``to_frd``).
FREQUENCY_RESULTS = {
    "twin.agard.df.DfResult",
    "twin.agard.compare.Comparison",
    "twin.agard.compare.PlatformDynamics",
    "twin.agard.omct.OmctResult",
    "twin.diagnose.diagnosis.DofReport",
    "twin.diagnose.diagnosis.Diagnosis",
}


def _classes_with_to_dict_or_plot() -> list[str]:
    """Scan the package's sources for classes defining ``to_dict`` or ``plot``."""
    found = []
    for path in sorted((ROOT / "twin").rglob("*.py")):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, ast.ClassDef):
                methods = {f.name for f in node.body if isinstance(f, ast.FunctionDef)}
                if methods & {"to_dict", "plot"}:
                    found.append(f"{module}.{node.name}")
    return found


def _load(qualified: str) -> type:
    module, name = qualified.rsplit(".", 1)
    return getattr(importlib.import_module(module), name)


def test_the_scan_finds_the_results():
    found = _classes_with_to_dict_or_plot()
    assert len(found) > 30
    assert {"twin.agard.df.DfResult", "twin.diagnose.diagnosis.Diagnosis"} <= set(found)
    assert not set(NOT_RESULTS) - set(found), "a class listed as no result is gone"


@pytest.mark.parametrize("qualified", _classes_with_to_dict_or_plot())
def test_every_class_with_to_dict_or_plot_follows_the_protocol(qualified):
    if qualified in NOT_RESULTS:
        cls = _load(qualified)
        assert not hasattr(cls, "plot"), f"{qualified} plots: make it a Result"
        return
    cls = _load(qualified)
    missing = [m for m in ("to_dict", "to_frame", "plot") if not callable(getattr(cls, m, None))]
    assert not missing, f"{qualified} lacks {missing}: a Result has to_dict, to_frame and plot"
    assert issubclass(cls, Result)
    params = list(inspect.signature(cls.plot).parameters.values())
    assert [p.name for p in params[:2]] == ["self", "ax"] and params[1].default is None
    assert all(p.kind is p.KEYWORD_ONLY for p in params[2:]), f"{qualified}.plot: keyword-only"
    assert "path" in [p.name for p in params[2:]]
    assert issubclass(cls, FrequencyResult) == (qualified in FREQUENCY_RESULTS), qualified


@pytest.fixture(scope="module")
def instances():
    sys.path.insert(0, str(Path(__file__).parent))
    from test_results_surface import RESULTS

    return {name: make() for name, make in RESULTS.items()}


@pytest.mark.parametrize(
    "name",
    ["Comparison", "DfResult", "ExperimentResult", "ForwardResult", "MonteCarloResult",
     "NoiseLevelResult", "OmctResult", "PilotFit", "PlatformDynamics", "SnrResult",
     "ThresholdResult"],
)  # fmt: skip
def test_a_result_draws_on_given_axes_and_gives_its_table(name, instances, tmp_path):
    r = instances[name]
    assert isinstance(r, Result)
    json.dumps(r.to_dict())
    table = r.to_frame()
    assert isinstance(table, pd.DataFrame) and len(table) > 0 and len(table.columns) > 1
    made = r.plot()
    assert isinstance(made, Figure) and made.axes
    mine = Figure()
    n = len([a for a in made.axes if a.get_label() != "<colorbar>"])
    axes = mine.subplots(1, n)
    fig = r.plot(axes, path=str(tmp_path / "on-mine.png"))
    assert fig is mine and (tmp_path / "on-mine.png").stat().st_size > 0
    drawn = axes if n > 1 else [axes]
    assert all(a.has_data() or a.patches or a.images or a.texts for a in drawn)


def test_a_plot_given_the_wrong_axes_says_how_many_it_needs(instances):
    fig = Figure()
    with pytest.raises(UsageError, match=r"ax: expected 2 Axes \(gain, phase\); got 1 item"):
        instances["OmctResult"].plot([fig.add_subplot()])
    with pytest.raises(UsageError, match="ax: expected one Axes; got str"):
        instances["ThresholdResult"].plot("left")


def test_to_frd_is_in_rad_s_at_the_result_s_frequencies(instances):
    df = instances["DfResult"]
    frd = df.to_frd()
    assert isinstance(frd, ct.FrequencyResponseData)
    assert np.allclose(frd.omega, 2 * np.pi * df.frequencies_hz)
    w = frd.omega[1]
    assert complex(frd.eval(w)) == pytest.approx(df.response[1])
    omct = instances["OmctResult"].to_frd()
    assert np.allclose(omct.omega, instances["OmctResult"].w_rad_s)
    cmp = instances["Comparison"]
    assert complex(cmp.to_frd(model="reduced").eval(w)) == pytest.approx(
        cmp.dofs["pitch"].reduced[1]
    )
    with pytest.raises(UsageError, match="has no 'roll'; it holds pitch"):
        cmp.to_frd("roll")


# --- units -----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["mpi", "srs", "condition-3"])
def test_response_at_hz_is_python_control_at_2_pi_f(name):
    f = np.array([0.05, 0.3, 1.0, 4.0])
    w = 2 * np.pi * f
    cfg = twin.configure(name)
    for dof in ("heave", "pitch"):
        m = cfg.transfer_function(dof)
        expected = np.array([complex(m.rational(1j * x)) for x in w]) * np.exp(-1j * w * m.delay_s)
        assert np.allclose(m.response_at_hz(f), expected, rtol=1e-12, atol=0)
        k = ["surge", "sway", "heave", "roll", "pitch", "yaw"].index(dof)
        assert np.allclose(cfg.response_at_hz(f)[:, k], expected, rtol=1e-12, atol=0)


def test_the_platform_filter_is_minus_6_db_at_its_break_in_hz_not_rad_s():
    from twin.chain.filter import PlatformFilter

    block = PlatformFilter(2.0)  # Eq 5.1 with a 2 Hz break
    h = block.response_at_hz([2.0])[0, 0]
    assert abs(h) == pytest.approx(0.5)
    tf = block.transfer_function(0)
    assert isinstance(tf, ct.TransferFunction)
    assert complex(tf(2j * np.pi * 2.0)) == pytest.approx(h)
    assert abs(complex(tf(2.0j))) > 0.9  # 2 rad/s is another frequency
    assert not hasattr(block, "frequency_response")
    assert not hasattr(twin.configure("mpi"), "frequency_response")


# --- no backend chosen -----------------------------------------------------------------------


def test_importing_the_twin_and_plotting_leave_the_backend_and_pyplot_alone():
    code = """
import matplotlib
matplotlib.use("svg")
import sys
import numpy as np
import twin
from twin.agard.df import DfResult
f = np.array([0.1, 1.0]); h = np.exp(-0.2j * f)
r = DfResult("pitch", f, h, {}, h, 0.035, 0.035, "synthetic", np.full(2, 1e-3), 0.05)
r.plot(path=sys.argv[1])
assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
assert "matplotlib.pyplot" not in sys.modules
print("ok")
"""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        done = subprocess.run([sys.executable, "-c", code, str(Path(tmp) / "df.png")],
                              cwd=ROOT, capture_output=True, text=True, timeout=120)  # fmt: skip
        assert done.returncode == 0, done.stderr
        assert done.stdout.strip() == "ok"
        assert (Path(tmp) / "df.png").read_bytes()[:4] == b"\x89PNG"


def test_import_twin_is_light_and_leaves_numpy_to_the_entry_points():
    """The ``twin`` command imports the package before it sets one BLAS thread.

    (:mod:`twin.core.threads`)
    """
    code = (
        "import sys, twin\n"
        "print(sorted(m for m in ('numpy', 'scipy', 'mujoco', 'matplotlib', 'pandas', 'control')"
        " if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
