"""The entry points of the :mod:`twin` namespace, one call each (:mod:`.entry_points`).

The top of the library beside the CLI: each function resolves a configuration given by name,
file or object and imports what it runs when called, so that ``import twin`` stays light.
"""
