"""The signal chain: pose commands -> filter -> delay -> noise -> platform -> virtual IMU.

Each block maps a :class:`twin.chain.trajectory.Trajectory` to one and reports its frequency
response; :mod:`twin.chain.config` names the platform configurations (``mpi``, ``srs``,
``condition-1`` ... ``condition-8``); :func:`twin.chain.simulate.simulate` runs a chain on the
full MuJoCo platform or the reduced one.
"""
