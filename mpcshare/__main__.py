"""``python -m mpcshare`` runs the ``mpcshare`` command line."""

import sys

from mpcshare.cli import main

if __name__ == "__main__":
    sys.exit(main())
