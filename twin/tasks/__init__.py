"""Batches of pure tasks on one process or a Dask cluster.

:mod:`.engine` runs them, :mod:`.outcome` holds what came back, :mod:`.sweep` runs a
parameter grid given as TOML; :mod:`.worker_setup` sets up a local cluster's worker processes.
"""
