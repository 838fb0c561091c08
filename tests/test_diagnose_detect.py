"""What "no finding" means (twin.diagnose.detect): the smallest effects stated, near zero too."""

from __future__ import annotations

import pytest

from twin.diagnose.detect import _both, _delay_text, _gain_text, _threshold


def test_a_bound_near_no_effect_is_found_and_shown_with_meaningful_digits():
    """Quiet data: a delay of 5 us or a gain 1.4e-4 from 1 would show. Before, the search
    stopped 10 us from no effect and the statements read 'a delay below -0 ms or above +0 ms'
    and 'a gain below 1.000 or above 1.000'."""

    def delay(v: float) -> float:  # the expected BIC gain over the margin: 0 at +-5 us
        return (v / 5e-6) ** 2 - 1

    def gain(g: float) -> float:  # 0 at 1 -+ 1.44e-4
        return ((g - 1) / 1.44e-4) ** 2 - 1

    less, more = _threshold(delay, 0.0, -0.03), _threshold(delay, 0.0, 0.3)
    assert (less, more) == (pytest.approx(-5e-6, rel=2e-3), pytest.approx(5e-6, rel=2e-3))
    low, high = _threshold(gain, 1.0, 0.1), _threshold(gain, 1.0, 10.0)
    assert low == pytest.approx(1 - 1.44e-4, abs=1e-7)
    assert high == pytest.approx(1 + 1.44e-4, abs=1e-7)
    assert _threshold(delay, 0.0, 3e-6) is None  # never reached: none would show
    assert (_both("delay", less, more, _delay_text)
            == "a delay below -5.0 µs or above +5.0 µs would have been found")  # fmt: skip
    assert (_both("gain", low, high, _gain_text)
            == "a gain below 0.99986 or above 1.00014 would have been found")  # fmt: skip
    # sizes well away from no effect read as before
    assert [_delay_text(v) for v in (0.027, -0.0015, 0.15)] == ["+27 ms", "-1.5 ms", "+150 ms"]
    assert [_gain_text(v) for v in (0.9, 1.25)] == ["0.900", "1.250"]
