"""``python -m rattle_lab``: the same command line as the ``rattle-lab`` script."""

import sys

from rattle_lab.cli import main

sys.exit(main())
