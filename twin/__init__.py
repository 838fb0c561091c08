"""Digital twin of flight-simulator motion systems after Nieuwenhuizen (2012).

The package follows the signal chain of the thesis: pose commands, platform filter, delay,
motion noise, platform (full MuJoCo model or reduced Eq 5.11 model) and virtual IMU:
:mod:`twin.platform` (models, geometry, kinematics), :mod:`twin.chain` (the signal chain),
:mod:`twin.agard` (AGARD-AR-144 tests), :mod:`twin.pilot` (pilots in the loop) and
:mod:`twin.diagnose` (what a recorded run says the twin gets wrong).

What a newcomer needs is here, one call each (:mod:`twin.api.entry_points`): :func:`configure`,
:func:`simulate`, :func:`describing_function`, :func:`agard_test`, :func:`session`,
:func:`compare`, :func:`diagnose_runs`, :func:`load_run`, :func:`workspace` and :func:`fly`. Those
that take a configuration take it as a name (``"mpi"``), a ``twin-config/1`` path or a
:class:`~twin.chain.config.MotionSystem` (what :func:`configure` returns); their model is the
reduced one unless ``model="full"`` (the commands' default is the full one). The analyses'
results (:func:`describing_function`, :func:`agard_test`, :func:`compare`,
:func:`diagnose_runs`) follow :class:`Result` (``to_dict``, ``to_frame``, ``plot``; ``to_frd``
for a frequency response: :class:`FrequencyResult`); runs, simulations and configurations
are data. ``import twin`` loads no NumPy: each entry
point imports the modules it runs (the ``twin`` command sets its BLAS threads first).

Examples
--------
>>> import twin
>>> ws = twin.workspace("mpi")
>>> round(float(ws["heave"].max - ws["heave"].min), 3)
0.501

"""

from twin.api.entry_points import (
    AGARD_TESTS,
    agard_test,
    compare,
    config_names,
    configure,
    describing_function,
    diagnose_runs,
    fly,
    load_run,
    session,
    simulate,
    workspace,
)
from twin.core.results import FrequencyResult, Result
from twin.core.version import __version__

__all__ = [
    "AGARD_TESTS",
    "FrequencyResult",
    "Result",
    "__version__",
    "agard_test",
    "compare",
    "config_names",
    "configure",
    "describing_function",
    "diagnose_runs",
    "fly",
    "load_run",
    "session",
    "simulate",
    "workspace",
]
