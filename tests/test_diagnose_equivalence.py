"""Explanations with the same response are one explanation said with more parameters."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from twin.chain.config import motion_system
from twin.chain.extensions import Extension
from twin.diagnose.candidates import extension_at_bounds, search_space
from twin.diagnose.equivalence import MIN_DF_GAIN_DB, MIN_DF_GAIN_DEG, SAME_RESPONSE, same_response
from twin.diagnose.select import _apart


def _case(platform: str) -> SimpleNamespace:
    """What the refit reads of a case: the nominal configuration (clean and as given)."""
    config = motion_system(platform)
    return SimpleNamespace(clean=config, config=config)


def _same(platform, named, effects, start):
    return same_response(named, effects, start, _case(platform), "heave", [])  # type: ignore[arg-type]


def test_a_resonance_damped_at_one_is_a_platform_filter_where_there_is_none():
    """SRS (no Eq 5.1 filter): w^2/(s^2 + 2 w s + w^2) = 1/(1 + s/w)^2 exactly."""
    named = [Extension("platform_filter", {"break_hz": 3.9}, ("heave",))]
    start = {"resonance": {"frequency_hz": 3.0, "damping": 0.8}}  # off, as a fit on noise is
    eq = _same("srs", named, ("resonance",), start)
    assert eq is not None
    assert eq["parameters"]["resonance"]["frequency_hz"] == pytest.approx(3.9, rel=1e-4)
    assert eq["parameters"]["resonance"]["damping"] == pytest.approx(1.0, rel=1e-4)
    assert eq["max_relative_difference"] < SAME_RESPONSE


def test_a_lead_cancelling_a_pole_of_a_critically_damped_resonance_is_a_first_order_filter():
    """(1 + T s) w^2 / (s + w)^2 with T = 1/w is w / (s + w): a sensor filter at w."""
    named = [Extension("sensor_filter", {"cutoff_hz": 2.5, "channels": ("az",)}, ("heave",))]
    start = {"lead": {"time_constant_s": 0.05}, "resonance": {"frequency_hz": 4.0, "damping": 0.9}}
    eq = _same("srs", named, ("lead", "resonance"), start)
    assert eq is not None
    res = eq["parameters"]["resonance"]
    # the searched damping ends at 1 (a mode; beyond, two lags): the pair is the double pole
    assert res["damping"] == pytest.approx(1.0, abs=1e-3)
    assert res["frequency_hz"] == pytest.approx(2.5, rel=1e-3)
    lead = eq["parameters"]["lead"]["time_constant_s"]
    assert lead == pytest.approx(1 / (2 * np.pi * 2.5), rel=1e-3)


def test_no_resonance_is_searched_beyond_critical_damping():
    """Damping above 1 is two real poles, not a mode: the search ends at 1, not at a bound."""
    space = search_space("resonance", None, "heave", [])  # type: ignore[arg-type]
    assert space.bounds[1][1] == 1.0
    assert float(np.max(space.grids[1])) <= 1.0
    critical = Extension("resonance", {"frequency_hz": 4.0, "damping": 1.0}, ("heave",))
    assert extension_at_bounds(critical, None, "heave", []) == []  # type: ignore[arg-type]
    light = Extension("resonance", {"frequency_hz": 4.0, "damping": 0.02}, ("heave",))
    assert [e["bound"] for e in extension_at_bounds(light, None, "heave", [])] == ["lower"]  # type: ignore[arg-type]


def test_the_same_response_is_what_no_named_effect_could_change():
    """SAME_RESPONSE is the least change a named effect makes, 0.1 dB or 0.5 deg at a line."""
    assert 20 * np.log10(1 + SAME_RESPONSE) <= MIN_DF_GAIN_DB + 1e-12
    assert np.degrees(np.arcsin(SAME_RESPONSE)) <= MIN_DF_GAIN_DEG + 1e-12
    assert SAME_RESPONSE == pytest.approx(np.sin(np.radians(0.5)))


def test_a_slightly_moved_mpi_filter_and_a_lead_with_a_lag_are_the_same_response():
    """The MPI's 1 Hz filter at 0.785 Hz: (1 + s/w1)^2/(1 + s/w0)^2 against (1 + Ts)/(1 + s/wc).

    They differ by about 0.15 % (0.013 dB) at most: less than any named effect changes.
    """
    named = [Extension("platform_filter", {"break_hz": 0.785}, ("heave",))]
    start = {"lead": {"time_constant_s": 0.05}, "sensor_filter": {"cutoff_hz": 1.0}}
    eq = _same("mpi", named, ("lead", "sensor_filter"), start)
    assert eq is not None
    assert 5e-4 < eq["max_relative_difference"] < 3e-3


@pytest.mark.parametrize(
    ("platform", "named", "effects", "start"),
    [
        # the MPI's own 1 Hz filter moved to 0.5 Hz: a lead and a first-order filter come
        # close over a band, but not everywhere
        (
            "mpi",
            [Extension("platform_filter", {"break_hz": 0.5}, ("heave",))],
            ("lead", "sensor_filter"),
            {"lead": {"time_constant_s": 0.05}, "sensor_filter": {"cutoff_hz": 1.0}},
        ),
        # a delay is not a lead at every frequency
        (
            "srs",
            [Extension("delay", {"extra_delay_s": 0.02}, ("heave",))],
            ("lead",),
            {"lead": {"time_constant_s": 0.0}},
        ),
        # a lightly damped resonance is not a critically damped filter
        (
            "srs",
            [Extension("resonance", {"frequency_hz": 6.0, "damping": 0.2}, ("heave",))],
            ("platform_filter",),
            {"platform_filter": {"break_hz": 6.0}},
        ),
    ],
)
def test_rivals_that_differ_somewhere_are_not_the_same(platform, named, effects, start):
    assert _same(platform, named, effects, start) is None


def test_a_backlash_is_compared_only_with_a_backlash():
    named = [Extension("backlash", {"play": 0.01}, ("heave",))]
    assert _same("srs", named, ("gain",), {"gain": {"gain": 0.9}}) is None


def test_the_same_motion_reaching_the_same_play_is_the_same_response():
    """SRS: a play behind a 2.1 Hz filter, or behind a resonance damped at one there."""
    play = Extension("backlash", {"play": 0.007}, ("heave",))
    named = [play, Extension("platform_filter", {"break_hz": 2.1}, ("heave",))]
    start = {"backlash": {"play": 0.0075}, "resonance": {"frequency_hz": 2.0, "damping": 0.9}}
    eq = _same("srs", named, ("backlash", "resonance"), start)
    assert eq is not None
    assert eq["parameters"]["backlash"]["play"] == 0.007  # the named play: the same one
    assert eq["parameters"]["resonance"]["frequency_hz"] == pytest.approx(2.1, rel=1e-4)
    assert eq["max_relative_difference"] < SAME_RESPONSE
    # a filter before the play is not a sensor's filter after it, whatever their responses
    sensor = {"backlash": {"play": 0.007}, "sensor_filter": {"cutoff_hz": 2.1}}
    assert _same("srs", named, ("backlash", "sensor_filter"), sensor) is None


def _gain(db_before, db_after, deg_before, deg_after):
    return {
        "df_error_db_before": db_before,
        "df_error_db_after": db_after,
        "df_error_deg_before": deg_before,
        "df_error_deg_after": deg_after,
    }


def test_an_effect_beside_another_must_change_the_held_out_describing_function():
    """A delay and a lead that cancel (0.05 dB, 0.1 deg together) are not named beside a lag."""
    from twin.diagnose.select import MIN_DF_GAIN_DB, MIN_DF_GAIN_DEG, _negligible

    gains = {
        "platform_lag": _gain(0.83, 0.06, 1.9, 0.2),
        "delay": _gain(0.11, 0.06, 0.3, 0.2),
        "lead": _gain(0.08, 0.06, 0.4, 0.2),
    }
    delta = {"platform_lag": 1e5, "delay": 563.0, "lead": 281.0}
    assert sorted(_negligible(gains, delta)) == ["delay", "lead"]
    # the strongest member is what the runs show: never dropped as negligible, even alone
    assert _negligible({"delay": _gain(0.11, 0.1, 0.3, 0.3)}, {"delay": 50.0}) == []
    # either measure is enough to matter
    gains["delay"] = _gain(0.07 + 1.5 * MIN_DF_GAIN_DB, 0.07, 0.3, 0.2)
    gains["lead"] = _gain(0.08, 0.06, 0.2 + 1.5 * MIN_DF_GAIN_DEG, 0.2)
    assert _negligible(gains, delta) == []


def test_the_same_response_says_how_far_apart():
    """Identical to the refit's precision, or within a stated per cent."""
    assert _apart(2.5e-11) == " (identical)"
    assert _apart(0.0015) == " (within 0.15 %)"


def test_the_same_response_at_one_filter_setting_is_not_at_another():
    """The MPI's filter moved to 0.79 Hz is a lead with a lag within 0.87 % at the nominal
    setting; with a run at the filter opened tenfold, the two differ where that run's lines
    are: no longer one explanation."""
    named = [Extension("platform_filter", {"break_hz": 0.79}, ("heave",))]
    start = {"lead": {"time_constant_s": 0.05}, "platform_lag": {"lag_s": 0.2}}
    case = _case("mpi")
    at_nominal = [SimpleNamespace(filter_scale=1.0)]
    eq = same_response(named, ("lead", "platform_lag"), start, case, "heave", at_nominal)  # type: ignore[arg-type]
    assert eq is not None and eq["max_relative_difference"] < SAME_RESPONSE
    both = [*at_nominal, SimpleNamespace(filter_scale=10.0)]
    assert same_response(named, ("lead", "platform_lag"), start, case, "heave", both) is None  # type: ignore[arg-type]
