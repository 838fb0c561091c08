"""Diagnose a recorded run: what the twin gets wrong, the cause, the extended model, the gain."""
