"""Sphinx configuration of the geotex documentation.

Build (from the repository root)::

    pip install ".[docs]" && sphinx-build -W docs docs/_build/html

Generated at build time (not committed): the CLI reference (walked from
``geotex.cli.build_parser``), one page per benchmark result in
``benchmarks/results/``, the API pages (autosummary) and the gallery
(sphinx-gallery runs every script in ``examples/``; set
``GEOTEX_EXAMPLES_QUICK=1`` for the quick mode, small inputs).  Partial builds
(quick checks, tests/test_docs_site.py): ``GEOTEX_EXAMPLES_ONLY=REGEX`` runs only
the examples whose file name matches, ``GEOTEX_DOCS_API=REGEX`` writes API pages
only for the modules whose name matches (e.g. ``geotex.viewpage``).  The 3D viewer
bundle is built from the npm registry when missing (``viewer/README.md``), and so
is MathJax (``npm --prefix docs ci``, pinned in ``docs/package.json``): the site
serves both itself and loads nothing from a CDN, so it works offline.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS))

import geotex  # noqa: E402
import geotex_sphinx  # noqa: E402

project = "geotex"
author = "the geotex authors"
copyright = "2026, the geotex authors"
release = geotex.__version__
version = release

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
    "geotex_sphinx",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "node_modules", "gallery/*.md", "README.md", "api.rst",
                    "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "auto_examples/*.md5", "auto_examples/*.codeobj.json"]
html_theme = "furo"
html_title = f"geotex {release}"
# the viewer bundle lands in _static/geotex-viewer.js
html_static_path = [str(ROOT / "geotex" / "data" / "viewer")]
templates_path = []

myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3

autodoc_default_options = {"members": True}
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

nitpicky = False
suppress_warnings = []

# --- gallery ------------------------------------------------------------------------
QUICK = os.environ.get("GEOTEX_EXAMPLES_QUICK") == "1"
ONLY = os.environ.get("GEOTEX_EXAMPLES_ONLY", "")     # e.g. "tiles|polycube" (regex)
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": rf"/({ONLY})" if ONLY else r"/",
    "ignore_pattern": r"__init__\.py" + (rf"|(^|/)(?!({ONLY}))[^/]*\.py$" if ONLY else ""),
    "reset_argv": "geotex_sphinx.example_argv",
    "image_scrapers": ("geotex_sphinx.output_scraper",),
    "reset_modules": (),
    "capture_repr": (),
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": True,
    "plot_gallery": "True",
    "show_memory": False,
    # the timing pages load jQuery and DataTables from a CDN (and differ in every build)
    "write_computation_times": False,
}


def _build_viewer_bundle():
    bundle = ROOT / "geotex" / "data" / "viewer" / "geotex-viewer.js"
    if bundle.exists() or not (ROOT / "viewer" / "package.json").exists():
        return
    npm = shutil.which("npm")
    if npm is None:
        raise RuntimeError("the 3D viewer bundle is missing and npm is not installed; "
                           "see viewer/README.md")
    subprocess.run([npm, "--prefix", str(ROOT / "viewer"), "ci", "--no-audit", "--no-fund"],
                   check=True)
    subprocess.run([npm, "--prefix", str(ROOT / "viewer"), "run", "build"], check=True)


_build_viewer_bundle()

# --- MathJax, served from the site (no CDN) ---------------------------------------------
#: the MathJax 3 component the pages load: TeX input with every extension built in (no
#: extension fetched later) and SVG output (no font files)
MATHJAX_FILE = "tex-svg-full.js"


def _mathjax_static_dir() -> Path:
    """Install MathJax from the npm registry when missing; return a static folder holding it."""
    source = DOCS / "node_modules" / "mathjax" / "es5" / MATHJAX_FILE
    how = ("npm --prefix docs ci (MathJax is pinned in docs/package.json and "
           "docs/package-lock.json; the site serves it, no CDN)")
    if not source.exists():
        npm = shutil.which("npm")
        if npm is None:
            raise RuntimeError(f"MathJax is missing ({source}) and npm is not installed; "
                               f"install Node.js and run {how}")
        done = subprocess.run([npm, "--prefix", str(DOCS), "ci", "--no-audit", "--no-fund"],
                              capture_output=True, text=True)
        if done.returncode != 0 or not source.exists():
            raise RuntimeError(f"MathJax is missing ({source}) and {how} failed: "
                               + (done.stderr.strip().splitlines() or ["no output"])[-1])
    static = DOCS / "generated" / "static"
    (static / "mathjax").mkdir(parents=True, exist_ok=True)
    shutil.copyfile(source, static / "mathjax" / MATHJAX_FILE)
    return static


html_static_path.append(str(_mathjax_static_dir()))
mathjax_path = f"mathjax/{MATHJAX_FILE}"         # relative: _static/mathjax/...
geotex_sphinx.write_api_page(only=os.environ.get("GEOTEX_DOCS_API", ""))
os.environ.setdefault("COLUMNS", "88")      # argparse help wraps at a fixed width
