"""``python -m emdm.cli``: the same as the ``emdm`` command."""

import sys

from .main import main

sys.exit(main())
