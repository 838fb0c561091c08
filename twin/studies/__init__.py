"""Studies over the analyses: parameter sweeps of AGARD tests and pilots.

``sweep`` (a TOML grid over configurations, run as tasks) and ``sweep_report`` (its tidy
table, points and figure).
"""
