"""Physical bounds of the chain's settings, in a module light enough for the command line.

The parser checks its options against these while it is built (:mod:`twin.cli.common`), so
they live apart from the blocks that use them (which import SciPy).
"""

#: Longest motion-system delay a configuration may have [s].
MAX_DELAY_S = 10.0
#: Lowest and highest break frequency a platform filter may have [Hz] (a 0.01 Hz filter
#: passes nothing a motion system moves; 1 kHz is above the 819.2 Hz IMU rate).
MIN_BREAK_HZ, MAX_BREAK_HZ = 0.01, 1000.0
