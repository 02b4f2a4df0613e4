"""``python -m core`` runs the ncperf command line."""

import sys

from core.cli import main

sys.exit(main())
