"""``python -m geotex`` runs the command line."""

import sys

from geotex.cli import main

if __name__ == "__main__":      # not when a spawned worker process re-imports it
    sys.exit(main())
