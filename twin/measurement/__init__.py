"""Measurement types shared by the analyses: describing functions, spectra, measurements.

``describing_function`` (Fourier coefficients at the excited lines, line noise from the
neighbouring bins, lag and delay fits) and ``measure`` (a :class:`~twin.measurement.measure.
Measurement`: IMU data, the commands and the signal's design, from a simulation or a run
folder). Used by :mod:`twin.agard` and :mod:`twin.diagnose` alike; imports nothing above it.
"""
