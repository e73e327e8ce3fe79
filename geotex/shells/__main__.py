"""``python -m geotex.shells [NAME ...]``: rebuild the shell catalog from its recipes."""

import sys

from geotex.shells.catalog import CATALOG_DIR, rebuild, recipes

for shell_name in sys.argv[1:] or sorted(recipes()):
    s = rebuild(shell_name, CATALOG_DIR / f"{shell_name}.npz")
    print(f"{shell_name}: {s.n_quads} quads, max height {s.max_height:.4g}")
