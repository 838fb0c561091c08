"""Batches of pure tasks on one process or a Dask cluster.

:mod:`.engine` runs them, :mod:`.outcome` holds what came back, :mod:`.sweep` runs a
parameter grid given as TOML; :mod:`.scheduler_probe` finds what answers at a scheduler
address, :mod:`.worker_setup` sets up a local cluster's worker processes.
"""
