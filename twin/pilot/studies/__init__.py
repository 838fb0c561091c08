"""Pilot studies: experiments, populations, replications, designs and Monte-Carlo runs.

``experiment`` (Chapter 6's conditions), ``population``, ``spread`` and ``identified``
(simulated subjects, measured as the thesis did), ``replication``, ``compare_settings`` and
``design`` (the thesis' result as a draw of the twin's; subjects an experiment needs),
``montecarlo`` (Chapter 2's FC versus ARX), ``condition_figure`` (Fig 6.5-6.9).
"""
