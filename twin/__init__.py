"""Digital twin of flight-simulator motion systems after Nieuwenhuizen (2012).

The package follows the signal chain of the thesis: pose commands, platform filter, delay,
motion noise, platform (full MuJoCo model or reduced Eq 5.11 model) and virtual IMU:
:mod:`twin.platform` (models, geometry, kinematics), :mod:`twin.chain` (the signal chain),
:mod:`twin.agard` (AGARD-AR-144 tests), :mod:`twin.pilot` (pilots in the loop) and
:mod:`twin.diagnose` (what a recorded run says the twin gets wrong).

Examples
--------
>>> from twin.platform import geometry, kinematics
>>> geo = geometry.load_geometry("mpi")
>>> ws = kinematics.workspace(geo)
>>> round(float(ws["heave"].max - ws["heave"].min), 3)
0.501

"""

__version__ = "0.1.0"
