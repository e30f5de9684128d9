"""``python -m hbm`` is the ``hbm`` command."""
import sys

from hbm.interface.cli import main

sys.exit(main())
