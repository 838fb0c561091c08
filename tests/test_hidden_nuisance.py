"""The generator's nuisances (opt-in) and the judge of a diagnosis against a draw's truth.

Without ``nuisance`` every draw is what it always was (the values below were recorded from the
generator before nuisances existed); with it, each draw varies the nominal's motion noise,
break frequency, amplitudes and window, from its seed alone.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from twin.chain.config import motion_system
from twin.chain.extensions import Extension
from twin.diagnose.hidden import (
    NUISANCE_RANGES,
    Nuisance,
    clean,
    draw,
    draw_nuisance,
    hidden_signal,
    judged,
    values_within_tolerance,
)


def test_the_old_arguments_draw_what_they_always_drew():
    """Seed 1001 (a delay) and 5003 (two effects): the fields recorded before the change."""
    h = draw(1001, "delay")
    assert (h.seed, h.config.name, h.dof, h.redraws, h.nuisance) == (1001, "srs", "roll", 0, None)
    assert [(e.effect, e.parameters, e.dofs) for e in h.extensions] == [
        ("delay", {"extra_delay_s": 0.023138270381735077}, ("roll",))
    ]
    assert h.imu_noise == 2.162774892608103
    assert h.truth.extensions == h.extensions and h.truth.filter_break_hz is None

    h = draw(5003, count=2)
    assert (h.seed, h.config.name, h.dof, h.redraws, h.nuisance) == (5003, "mpi", "heave", 0, None)
    assert [(e.effect, e.parameters, e.dofs) for e in h.extensions] == [
        ("platform_filter", {"break_hz": 1.5277855576554393}, ("heave",)),
        ("gain", {"gain": 1.3329671773761134}, ("heave",)),
    ]
    assert h.imu_noise == 1.555386926849318
    assert h.truth.filter_break_hz == 1.0 and h.truth.noise_scale == 1.0

    c = clean(210, (0.3, 3.0))
    assert (c.config.name, c.dof, c.imu_noise, c.nuisance) == ("mpi", "pitch", 1.4483075039028241,
                                                                None)  # fmt: skip


def _values(n: Nuisance) -> tuple[float, float, float, int]:
    return (n.motion_noise, n.filter_break, n.amplitude, n.periods)


def test_nuisances_follow_the_seed_and_differ_between_seeds():
    """Same seed, same nuisances; another seed, others; within the ranges; in the truth."""
    a, b = clean(210, (0.3, 3.0), nuisance=True), clean(211, (0.3, 3.0), nuisance=True)
    again = clean(210, (0.3, 3.0), nuisance=True)
    assert a.nuisance is not None and b.nuisance is not None
    assert _values(a.nuisance) == _values(again.nuisance)  # type: ignore[union-attr]
    assert _values(a.nuisance) != _values(b.nuisance)
    assert (a.config.name, a.dof, a.imu_noise) == ("mpi", "pitch", 1.4483075039028241)  # as off
    mpi = motion_system("mpi")
    for seed in range(20):
        n = draw_nuisance(seed, 0, mpi)
        assert NUISANCE_RANGES.motion_noise[0] <= n.motion_noise <= NUISANCE_RANGES.motion_noise[1]
        assert abs(n.filter_break - 1) <= NUISANCE_RANGES.filter_break
        assert NUISANCE_RANGES.amplitude[0] <= n.amplitude <= NUISANCE_RANGES.amplitude[1]
        assert n.periods in NUISANCE_RANGES.periods
    n = a.nuisance
    assert a.truth.filter_break_hz == pytest.approx(n.filter_break)  # the MPI's 1 Hz, moved
    assert a.truth.noise_scale == pytest.approx(n.motion_noise)
    assert a.config == mpi  # what meta.json names: the nominal
    d1, d2 = draw(1001, "delay", nuisance=True), draw(1001, "delay", nuisance=True)
    assert d1 == d2 and d1.nuisance is not None  # the same seed, the same draw
    assert d1.extensions == draw(1001, "delay").extensions  # its own stream: the same effect
    srs = draw_nuisance(3, 0, motion_system("srs"))  # no filter, no motion noise to vary
    assert (srs.motion_noise, srs.filter_break) == (1.0, 1.0)
    sig = hidden_signal(1, "heave", Nuisance(1.0, 1.0, 0.5, 2))
    full = hidden_signal(1, "heave")
    assert sig.window[1] - sig.window[0] == pytest.approx(40.0)
    assert sig.amplitudes == pytest.approx(0.5 * full.amplitudes)


def _f(
    effect: str,
    ambiguous: bool = False,
    alternatives: tuple[tuple[str, ...], ...] = (),
    named_set: tuple[str, ...] | None = None,
) -> SimpleNamespace:
    """A finding as the judge reads it: its effect, flag, named set and alternatives."""
    evidence = {
        "set": list(named_set or (effect,)),
        "ambiguous": ambiguous,
        "alternatives": [{"effects": list(a)} for a in alternatives],
    }
    return SimpleNamespace(
        extension=SimpleNamespace(effect=effect), evidence=evidence, ambiguous=ambiguous
    )


@pytest.mark.parametrize(
    ("truth", "findings", "verdict"),
    [
        (("delay",), [_f("delay")], "right"),
        (("delay",), [_f("noise"), _f("delay")], "right"),  # the nuisance's motion noise
        (("delay",), [_f("lead", True, [("delay",)])], "ambiguous"),
        (("delay",), [_f("delay", True, [("lead",)])], "ambiguous"),
        (("delay",), [_f("lead")], "wrong"),
        (("delay",), [_f("lead", True, [("platform_filter",)])], "wrong"),
        (("delay",), [], "none"),
        (("delay",), [_f("noise")], "none"),
        (("noise",), [_f("noise")], "right"),
        (("gain", "delay"), [_f("gain", named_set=("delay", "gain")), _f("delay")], "right"),
        (("gain", "delay"), [_f("gain")], "none"),  # one of the two, nothing false
        (("gain", "delay"), [_f("lead"), _f("gain")], "wrong"),
        (
            ("gain", "delay"),
            [_f("lead", True, [("gain", "delay")], ("lead", "gain"))],
            "ambiguous",
        ),
        ((), [], "right"),
        ((), [_f("noise")], "right"),  # motion noise is not a dynamic cause
        ((), [_f("gain")], "wrong"),
        ((), [_f("gain", True, [("delay",)])], "wrong"),
    ],
)
def test_the_judge(truth, findings, verdict):
    """right / ambiguous / wrong / none on hand-built findings."""
    h = SimpleNamespace(effects=truth, dof="heave", nuisance=None)  # what the judge reads
    assert judged(h, SimpleNamespace(findings=findings)) == verdict  # type: ignore[arg-type]


def _filter(break_hz: float, ambiguous: bool = False) -> SimpleNamespace:
    f = _f("platform_filter", ambiguous, [("lead", "sensor_filter")] if ambiguous else [])
    f.extension = SimpleNamespace(effect="platform_filter", value=lambda name: break_hz)
    return f


@pytest.mark.parametrize(
    ("truth", "findings", "verdict"),
    [
        ((), [_filter(1.06)], "right"),  # the moved break itself: a real difference
        ((), [_filter(1.06, ambiguous=True)], "ambiguous"),
        ((), [_filter(1.5)], "wrong"),  # a filter, but not where the nuisance moved it
        (("delay",), [_f("delay"), _filter(1.04)], "right"),
        (("delay",), [_filter(1.04), _f("delay")], "right"),
        (("delay",), [_filter(1.04)], "none"),  # the nuisance named, the effect missed
        (("delay",), [_f("gain"), _filter(1.04)], "wrong"),
    ],
)
def test_the_judge_counts_the_moved_filter(truth, findings, verdict):
    """With the nuisances' break at 1.05 x the MPI's 1 Hz, a filter found there is true."""
    h = SimpleNamespace(
        effects=truth,
        dof="heave",
        nuisance=Nuisance(filter_break=1.05),
        config=SimpleNamespace(filter_break_hz=1.0),
    )
    assert judged(h, SimpleNamespace(findings=findings)) == verdict  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("named", "close"),
    [
        ({"delay": 0.024, "gain": 0.93}, True),
        ({"delay": 0.0245, "gain": 0.9}, True),  # 4.5 ms off; 0.9 is 3 % off 0.93
        ({"delay": 0.026, "gain": 0.93}, False),  # 6 ms off (5 ms allowed)
        ({"delay": 0.02, "gain": 0.7}, False),  # 25 % off (20 % allowed)
        ({"delay": 0.02}, False),  # the gain not named
    ],
)
def test_values_within_the_tolerance(named, close):
    """A named effect counts only with its values near the truth's (5 ms for a delay, 20 %)."""
    delay = Extension("delay", {"extra_delay_s": 0.02}, ("heave",))
    gain = Extension("gain", {"gain": 0.93}, ("heave",))
    h = SimpleNamespace(extensions=(delay, gain), dof="heave")
    findings = [
        SimpleNamespace(extension=Extension("delay", {"extra_delay_s": v}, ("heave",)))
        if e == "delay" else SimpleNamespace(extension=Extension("gain", {"gain": v}, ("heave",)))
        for e, v in named.items()
    ]  # fmt: skip
    assert values_within_tolerance(h, findings) is close  # type: ignore[arg-type]
