"""The ``twin`` command line: argparse glue over the library, one module per command group.

A ``twin`` process uses one BLAS thread (:mod:`twin.core.threads`), set here before anything
imports NumPy.
"""

from twin.core.threads import single_blas_thread

single_blas_thread()
