"""The twin's version: written into every file it owns and checked against remote workers."""

__version__ = "0.1.0"
