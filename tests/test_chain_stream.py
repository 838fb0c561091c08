"""One causal chain: every block streams, and open and closed loop drive the same chain."""

import numpy as np
import pytest
from configurations import everything

from twin.chain.block import Backlash, Gain, Lead
from twin.chain.config import motion_system
from twin.chain.delay import Delay
from twin.chain.extensions import Extension
from twin.chain.filter import PlatformFilter
from twin.chain.jets import JetSignal
from twin.chain.lti import LtiBlock
from twin.chain.physics import FullPlatform
from twin.chain.reduced import ReducedPlatform
from twin.chain.simulate import prepare
from twin.chain.stream import ChainStream
from twin.chain.trajectory import Trajectory
from twin.core.errors import SignalError


def _commands(seconds: float, rate: float = 100.0) -> Trajectory:
    """Heave and pitch multi-sines with a fade-in (any non-trivial smooth command)."""
    t = np.arange(round(seconds * rate) + 1) / rate
    fade = np.clip(t / 1.5, 0, 1)
    v = np.zeros((t.size, 6))
    v[:, 2] = fade * (0.02 * np.sin(2 * np.pi * 0.35 * t) + 0.004 * np.sin(2 * np.pi * 2.15 * t))
    v[:, 4] = fade * (0.03 * np.sin(2 * np.pi * 0.55 * t) + 0.005 * np.sin(2 * np.pi * 3.35 * t))
    v[:, 0] = fade * 0.01 * np.sin(2 * np.pi * 0.8 * t)
    return Trajectory(rate, v)


BLOCKS = [
    PlatformFilter(1.0),
    PlatformFilter((1.0, None, 2.0, 5.0, 0.7, None)),
    LtiBlock(((1.0,), (1 / (2 * np.pi * 7) ** 2, 2 * 0.3 / (2 * np.pi * 7), 1.0))),
    LtiBlock(((0.5, 1.0), (0.1, 1.0))),  # proper, with a direct feed-through
    Delay(0.035),
    Delay((0.0, 0.0123, 0.025, 0.1, 0.0005, 0.01)),
    Lead((0.0, 0.0, 0.023, 0.0, 0.027, 0.01)),
    Gain(0.8, (False, False, True, False, True, False)),
    Backlash(0.002, (False, False, True, False, True, False)),
]


@pytest.mark.parametrize("block", BLOCKS, ids=lambda b: b.name)
def test_every_block_streamed_sample_by_sample_equals_its_whole_form_to_1e_12(block):
    sig = JetSignal.from_trajectory(_commands(6.0))
    whole = block(sig).jets
    state = block.start(sig.jets[:, 0], sig.rate_hz)
    parts = []
    for k in range(sig.n):
        out, state = block.stream(sig.jets[:, k : k + 1], state)
        parts.append(out)
    assert np.abs(np.concatenate(parts, axis=1) - whole).max() < 1e-12


@pytest.mark.parametrize("f_hz", [0.35, 2.15, 6.85])
def test_linear_blocks_follow_their_frequency_response_within_0_01_db_and_0_1_deg(f_hz):
    # steady-state sine through each linear block vs its continuous response (Eq 5.1 etc.)
    rate = 100.0
    t = np.arange(4001) / rate
    v = np.outer(np.sin(2 * np.pi * f_hz * t), np.ones(6))
    sig = JetSignal.from_trajectory(Trajectory(rate, v))
    late = t > 20.0
    basis = np.exp(-2j * np.pi * f_hz * t[late])
    for block in BLOCKS[:8]:
        y = block(sig).jets[0, late, :, 0]
        h_meas = 2 * (basis @ y) / late.sum() / (-1j)  # sin -> complex amplitude
        h = block.response_at_hz([f_hz])[0]
        assert np.all(np.abs(20 * np.log10(np.abs(h_meas / h))) < 0.01), block.name
        assert np.all(np.abs(np.angle(h_meas / h, deg=True)) < 0.1), block.name


@pytest.mark.parametrize(("model", "seconds"), [("reduced", 12.0), ("full", 3.0)])
def test_open_and_closed_loop_drive_the_same_chain_to_numerical_precision(model, seconds):
    """Every block and extension, the noise and the limits: the open-loop run (10 s chunks)
    and the chain stepped one command sample at a time, as a pilot loop steps it, give the
    same platform motion (1e-9 m and rad)."""
    cfg = everything()
    cmd = _commands(seconds)
    run = prepare(cfg, cmd, model, seed=4)
    open_loop = run.collect().response
    platform = FullPlatform("srs") if model == "full" else ReducedPlatform("srs")
    chain = ChainStream(cfg, platform, cmd.rate_hz, seed=4)
    sig = JetSignal.from_trajectory(cmd)
    steps = [chain.step(sig.jets[:, k : k + 1]).run(0) for k in range(sig.n)]
    poses = np.concatenate([s.pose for s in steps])
    commands = np.concatenate([s.command for s in steps])
    assert poses.shape == open_loop.pose.shape
    assert np.abs(poses - open_loop.pose).max() < 1e-9
    assert np.abs(commands - open_loop.command).max() < 1e-9
    assert chain.report.samples == run.limits.samples
    # and the chain did act: the extensions changed the platform input
    plain = prepare(motion_system("condition-8"), cmd, model, seed=4).collect().response
    assert np.abs(plain.command[:, 4] - open_loop.command[:, 4]).max() > 1e-4


def test_the_pilot_flies_the_configurations_extensions():
    # a gain extension of 0.5 on pitch and heave halves the felt attitude (no noise, no
    # delay difference): the pilot loop composes the configuration's own blocks
    from twin.pilot.models.pitch import PitchPilot, simulate_pitch

    base = motion_system("srs")
    half = base.replace(extensions=(Extension("gain", {"gain": 0.5}, ("pitch", "heave")),))
    a = simulate_pitch(PitchPilot(), base, seed=1)
    b = simulate_pitch(PitchPilot(), half, seed=1)
    ratio_a = np.std(a.theta_felt) / np.std(a.theta)
    ratio_b = np.std(b.theta_felt) / np.std(b.theta)
    assert ratio_a == pytest.approx(1.0, abs=0.05)
    assert ratio_b == pytest.approx(0.5, abs=0.03)


def test_chain_stream_rejects_bad_commands():
    chain = ChainStream("srs", ReducedPlatform("srs"), 100.0)
    with pytest.raises(SignalError, match=r"jets of shape \(1, n, 6, 3\)"):
        chain.step(np.zeros((1, 5, 6)))
    bad = np.zeros((1, 2, 6, 3))
    bad[0, 1, 2, 0] = np.nan
    with pytest.raises(SignalError, match="finite"):
        chain.step(bad)
    with pytest.raises(SignalError, match=r"drives the mpi platform, not .srs."):
        ChainStream("mpi", ReducedPlatform("srs"), 100.0)


def test_every_block_has_its_transfer_function_in_python_control():
    """Each linear block exposes a python-control transfer function; multiplied (with the
    delays kept exact) they give the configuration's reduced model to 1e-12 in every DOF,
    for a chain that uses every block and extension; backlash has none and says so."""
    import control

    from twin.chain.block import Backlash
    from twin.core.errors import SignalError

    cfg = everything()
    f = np.geomspace(0.02, 30.0, 120)
    h = cfg.response_at_hz(f)
    for k in range(6):
        model = cfg.transfer_function(k)
        assert isinstance(model.rational, control.TransferFunction)
        assert np.max(np.abs(model.response_at_hz(f) - h[:, k])) < 1e-12
    # python-control's own analysis applies: the 1 Hz filter is a double pole at 2 pi rad/s
    surge = motion_system("mpi").transfer_function("surge").rational
    assert np.allclose(surge.poles(), -2 * np.pi) and control.dcgain(surge) == pytest.approx(1)
    with pytest.raises(SignalError, match="no transfer function"):
        Backlash(0.001, (True,) * 6).transfer_function(0)
