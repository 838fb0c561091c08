"""Measured logs into the twin's run format: columns, units, time bases, clocks, IMU mount.

:func:`~twin.ingest.importer.import_run` (``twin import``) reads CSV logs as a lab writes
them and writes a ``twin-run/1`` folder, stating what it assumed and estimated.
"""

from twin.ingest.importer import Clock, ImportReport, import_run

__all__ = ["Clock", "ImportReport", "import_run"]
