"""Digital twin of flight-simulator motion systems after Nieuwenhuizen (2012).

The package follows the signal chain of the thesis: pose commands, platform filter, delay,
motion noise, platform (full MuJoCo model or reduced Eq 5.11 model) and virtual IMU. This
release holds the foundation: the platform models, their geometry and their kinematics.

Examples
--------
>>> from twin import kinematics, geometry
>>> geo = geometry.load_geometry("mpi")
>>> ws = kinematics.workspace(geo)
>>> round(ws["heave"].max - ws["heave"].min, 3)
0.501

"""

__version__ = "0.1.0"
