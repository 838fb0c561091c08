"""The ``twin`` command line: argparse glue over the library, one module per command group."""
