"""The ``emdm`` command line: one error boundary around every command."""

from .main import main

__all__ = ["main"]
