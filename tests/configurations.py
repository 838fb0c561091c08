"""Configurations shared by several test files."""

from twin.chain.config import MotionSystem, motion_system
from twin.chain.extensions import Extension


def everything() -> MotionSystem:
    """Condition 8 on the SRS (1 Hz filter, 100 ms, noise) with its resonance and every
    extension of the vocabulary: a configuration that uses every block."""
    ext = (
        Extension("delay", {"extra_delay_s": 0.012}, ("heave",)),
        Extension("gain", {"gain": 0.9}, ("pitch",)),
        Extension("platform_filter", {"break_hz": 2.5}, ("surge",)),
        Extension("resonance", {"frequency_hz": 7.0, "damping": 0.3}, ("heave", "pitch")),
        Extension("lead", {"time_constant_s": 0.01}, ("pitch",)),
        Extension("backlash", {"play": 0.0005}, ("heave",)),
        Extension("sensor_filter", {"cutoff_hz": 8.0, "channels": ("q",)}),
        Extension("noise", {"scale": 1.5}),
    )
    return motion_system("condition-8").replace(name="everything", resonance=True, extensions=ext)
