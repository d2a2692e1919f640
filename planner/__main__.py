"""``python -m planner`` runs the ``minkplan`` command line."""

import sys

from .cli import main

sys.exit(main())
