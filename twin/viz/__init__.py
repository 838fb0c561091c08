"""Views of results: Rerun recordings (:mod:`twin.viz.record`, the only importer of rerun)."""
