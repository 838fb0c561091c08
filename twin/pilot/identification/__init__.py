"""Pilot identification: FC, ARX, model fits and the honest bounds of a time-domain MLE.

``fc`` and ``arx`` (frequency responses from runs), ``fit`` (model parameters from them),
``mle`` (the pitch pilot fitted in the time domain), ``minima``, ``selection``, ``profile`` and
``profile_wald`` (the bounds that hold), ``felt_motion`` (which motion system a run was flown
through). Builds on :mod:`twin.pilot.models` only.
"""
