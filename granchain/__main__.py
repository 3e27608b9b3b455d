"""python -m granchain: the command line (granchain.cli)."""

import sys

from granchain.cli import main

sys.exit(main())
