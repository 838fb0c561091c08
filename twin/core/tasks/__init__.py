"""Batches of pure tasks on one process or a Dask cluster.

:mod:`.engine` runs them, :mod:`.outcome` holds what came back; :mod:`.scheduler_probe` finds
what answers at a scheduler address, :mod:`.worker_setup` sets up a local cluster's worker
processes. The sweeps built on them are in :mod:`twin.studies`.
"""
