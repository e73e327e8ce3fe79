"""``python -m geotex`` runs the command line."""

import sys

from geotex.cli import main

sys.exit(main())
