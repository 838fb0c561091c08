"""The core every room builds on: errors, checks, frames, files, progress, threads, tasks.

``errors`` (the error taxonomy), ``checks`` (input checks), ``frames`` (the thesis' frames and
DOF names), ``thesis`` (numbers the thesis prints), ``lifecycle`` and ``ownership`` (outputs
written whole, files the twin owns), ``interrupts``, ``progress``, ``threads`` (one BLAS
thread), ``jsonable``, ``plotting`` (figures on Figure objects or the caller's axes; no
backend chosen), ``results`` (the result protocol) and :mod:`twin.core.tasks` (batches of
pure tasks on one process or a Dask cluster). Imports nothing of the twin outside ``core``
(the version lives in :mod:`twin.core.version`).
"""
