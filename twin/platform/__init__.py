"""The platforms: names and facts, geometry from the compiled MJCF, kinematics, model building.

``facts`` (platform names, model files, ``platform.toml``), ``geometry`` (read from the MJCF),
``kinematics`` (App. A: inverse, Jacobian, forward, leg rates, workspace), ``build``
(``build.toml`` -> MJCF), ``neutral_fit`` (the SRS neutral height, Table 5.1) and
``workspace`` (workspace tables).
"""
