"""The twin's file formats: run folders, their checks, and test schedules.

``runs`` (``twin-run/1`` folders: reading, writing, checking), ``run_folder`` (a simulated
run streamed into a folder, its ``meta.json``), ``run_checks`` and ``run_expected`` (a
recorded run's plausibility against the nominal twin's reading of its commands) and
:mod:`twin.formats.schedule` (movement series and ``twin-schedule/1`` TOML schedules).
"""
