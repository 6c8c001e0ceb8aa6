"""`python -m kvrod`."""

import sys

from kvrod.cli import main

sys.exit(main())
