"""Measurement types shared by the analyses: describing functions, spectra, measurements.

``describing_function`` (Fourier coefficients at the excited lines, line noise from the
neighbouring bins, lag and delay fits), ``measure`` (a :class:`~twin.measurement.measure.
Measurement`: IMU data, the commands and the signal's design, from a simulation or a run
folder; the noise-free measurement of a configuration) and ``periodic`` (a periodic run's
excited lines and window of whole periods, from its ``meta.json`` or inferred from its
commands). Used by :mod:`twin.agard`, :mod:`twin.diagnose` and :mod:`twin.ingest` alike;
imports nothing above it.
"""
