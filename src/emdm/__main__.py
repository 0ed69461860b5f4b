"""``python -m emdm``: the same as the ``emdm`` command."""

from .entry import console

console()
