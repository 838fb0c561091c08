"""What "no finding" means (twin.diagnose.detect): the smallest effects stated, near zero too."""

from __future__ import annotations

import pytest

from twin.chain.config import motion_system
from twin.chain.extensions import Extension
from twin.diagnose.detect import _both, _delay_text, _gain_text, _threshold
from twin.diagnose.diagnosis import diagnose
from twin.diagnose.hidden import record_runs


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


@pytest.fixture(scope="module")
def heave_backlash_threshold(tmp_path_factory):
    """The smallest play a clean MPI heave pair of runs could show (stated by the diagnosis)."""
    mpi = motion_system("mpi")
    runs = record_runs(mpi, mpi, "heave", tmp_path_factory.mktemp("clean"), 5)
    d = diagnose(runs, seed=5)
    entry = d.dofs["heave"].detectable["backlash"]
    assert "backlash above" in entry["statement"] and "mm of play" in entry["statement"]
    return mpi, entry["value"]


@pytest.mark.slow
@pytest.mark.parametrize(("factor", "named"), [(0.3, False), (3.0, True)])
def test_the_stated_backlash_threshold_means_what_it_says(
    heave_backlash_threshold, tmp_path, factor, named
):
    """A play at 0.3 x the stated threshold is not named; at 3 x it is (the same runs' design,
    another seed)."""
    mpi, play = heave_backlash_threshold
    ext = Extension("backlash", {"play": factor * play}, ("heave",))
    runs = record_runs(mpi.replace(extensions=(ext,)), mpi, "heave", tmp_path, 6)
    found = {f.extension.effect for f in diagnose(runs, seed=6).findings}
    assert ("backlash" in found) is named, found
