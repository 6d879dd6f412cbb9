"""``python -m formation_ftc`` runs the ``formation-ftc`` command line."""

import sys

from formation_ftc.cli import main

if __name__ == "__main__":
    sys.exit(main())
