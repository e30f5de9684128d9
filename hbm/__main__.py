"""``python -m hbm`` is the ``hbm`` command."""
import sys

from .cli import main

sys.exit(main())
