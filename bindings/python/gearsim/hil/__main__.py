"""python -m gearsim.hil ...: the ``gearsim hil`` command standalone."""

import sys

from .cli import main

sys.exit(main())
