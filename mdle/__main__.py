"""``python -m mdle`` runs the command line."""

import sys

from mdle.cli import main

sys.exit(main())
