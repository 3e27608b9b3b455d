"""python -m granchain.cli"""

import sys

from granchain.cli import main

sys.exit(main())
