"""python -m granchain.reproduce: the same as `granchain reproduce`."""

import sys

from granchain.reproduce import main

if __name__ == "__main__":
    sys.exit(main())
