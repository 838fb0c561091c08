"""Rerun recordings: the only package that imports rerun.

One module per recording kind, each with its layout (blueprint):

- :mod:`twin.viz.record.platform`: platform runs (``twin simulate --rrd``, ``twin agard``: an
  AGARD session's from :func:`bench_recorder`), the platform in 3D from its MJCF, the pose,
  legs and IMU as series, describing functions;
- :mod:`twin.viz.record.pilot`: pilot-in-the-loop runs (``twin pilot run --rrd``);
- :mod:`twin.viz.record.diagnosis`: a diagnosis (``twin diagnose``: measured, nominal and extended
  responses overlaid);

and what they share: :mod:`twin.viz.record.stream` (a recording's file written under a partial
name and renamed when complete; series styles), :mod:`twin.viz.record.spectra` (frequency
responses on the ``frequency_mHz`` timeline and figures as images), :mod:`twin.viz.record.read`
(reading an ``.rrd`` back, for checks and tests).
"""

from twin.viz.record.platform import Recorder, bench_recorder, blueprint
from twin.viz.record.read import read_archetypes, read_entities, read_timelines

__all__ = [
    "Recorder",
    "bench_recorder",
    "blueprint",
    "read_archetypes",
    "read_entities",
    "read_timelines",
]
