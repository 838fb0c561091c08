"""Simulations a diagnosis runs side by side give the bits they give one after the other."""

from __future__ import annotations

import numpy as np
import pytest

import twin.core.threads
from twin.chain.config import motion_system
from twin.chain.signals import describing_signal
from twin.chain.simulate import prepare
from twin.diagnose.candidates import Model, make_extension
from twin.diagnose.data import Case, measurement_channels, nominal_imu
from twin.formats.run_folder import signal_meta
from twin.measurement.measure import from_imu


def _measurement(platform: str, dof: str):
    config = motion_system(platform)
    sig = describing_signal(1, dof, settle_s=None)
    imu = nominal_imu({}, platform)
    sim = prepare(config, sig.commands, "reduced", 3, imu).collect()
    return config, imu, from_imu(sig.commands, sim.imu, "run", config, {"signal": signal_meta(sig)})


def _same(a, b) -> bool:
    return a.shape == b.shape and bool((a.view(np.int64) == b.view(np.int64)).all())


@pytest.fixture
def one_thread(monkeypatch):
    def use_one():
        monkeypatch.setattr(twin.core.threads, "SIMULATION_THREADS", 1)

    return use_one


def test_noise_realisations_side_by_side_are_those_one_after_the_other(one_thread):
    config, imu, m = _measurement("mpi", "heave")  # motion noise: a simulation per seed
    together = measurement_channels(m, config, "reduced", imu, seed=2, realisations=2)
    one_thread()
    alone = measurement_channels(m, config, "reduced", imu, seed=2, realisations=2)
    for a, b in zip(together, alone, strict=True):
        assert a.sources[0].any() and _same(a.sources, b.sources) and _same(a.nominal, b.nominal)


def test_plays_simulated_side_by_side_are_the_bases_one_after_the_other(one_thread):
    config, imu, m = _measurement("srs", "pitch")
    channels = measurement_channels(m, config, "reduced", imu, seed=1, realisations=2)
    case = Case(config, "reduced", imu, channels, 1)
    plays = [1e-4, 3e-3, 2e-2]

    def with_play(model: Model, p: float) -> Model:
        return model.with_(make_extension("backlash", ["play"], [p], "pitch"))

    model = Model(case, "pitch")
    model.prefetch(plays, channels)
    assert len(model._cache) == len(plays)  # simulated, not yet asked for
    together = [with_play(model, p).base(channels[0]) for p in plays]
    assert len(model._cache) == len(plays)
    one_thread()
    alone = [with_play(Model(case, "pitch"), p).base(channels[0]) for p in plays]
    assert all(_same(a, b) for a, b in zip(together, alone, strict=True))
    assert not _same(together[0], together[2])


@pytest.mark.parametrize("seed", range(3))
def test_the_plays_simulated_ahead_are_the_first_two_the_search_asks_for(seed):
    """_brent_start predicts SciPy's bounded search (its first two points need no values)."""
    from twin.diagnose.candidates import PLAY_XATOL, Space, _brent_start, _refine

    rng = np.random.default_rng(seed)
    lo = float(np.exp(rng.uniform(-9, -3)))
    hi = lo * float(np.exp(rng.uniform(0.1, 2.0)))
    centre = float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
    asked, ahead = [], []
    space = Space(("play",), (np.array([lo]),), ((lo / 10, hi * 10),))
    _refine(lambda p: asked.append(p) or (np.log(p / centre)) ** 2, lo, hi, space, ahead.extend)
    assert ahead == asked[:2] and len(asked) > 4
    a, b = np.log(lo), np.log(hi)
    assert [float(np.exp(u)) for u in _brent_start(a, b, PLAY_XATOL)] == asked[:2]
