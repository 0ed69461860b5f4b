"""``python -m emdm.cli``: the same as the ``emdm`` command."""

from .main import console

console()
