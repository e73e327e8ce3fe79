"""The built documentation site, opened in headless Chromium.

A small site is built once per run (``sphinx-build -W`` on a copy of
``docs/``, so that the source tree is left alone): one gallery example
(``GEOTEX_EXAMPLES_ONLY``, an example that writes a textured GLB) and the API
page of one module (``GEOTEX_DOCS_API``); every hand-written page, the CLI
reference and the benchmark pages are in it. The gallery page must show its
model in the embedded 3D viewer, and the home page must load without a
console error or a missing local file.

Like tests/test_viewer.py: under CI (``CI`` set) Sphinx, Chromium, playwright
and the viewer bundle are required (.ci/run installs them, the ``test`` extra
pulls in Sphinx); elsewhere the tests skip when one is missing.
"""

from __future__ import annotations

import io
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import unquote, urlparse

import numpy as np
import pytest
from PIL import Image

from geotex.viewpage import viewer_bundle_path
from test_viewer import CHROMIUM, UNDER_CI, chromium_page

ROOT = Path(__file__).resolve().parents[1]
#: the example of the small site: a textured torus written as GLB (and OBJ), quick
EXAMPLE = "textured_export"
#: the one module that gets an API page
API_MODULE = "geotex.viewpage"
DOCS_PACKAGES = ("sphinx", "sphinx_gallery", "numpydoc", "myst_parser", "furo")

pytestmark = pytest.mark.slow      # the build: ~15-30 s on 2 cores


def _need(what: str, ok: bool):
    if ok:
        return
    if UNDER_CI:
        pytest.fail(f"{what} is required under CI (.ci/run installs it)")
    pytest.skip(f"{what} is not available")


def _installed(module: str) -> bool:
    try:
        __import__(module)
    except ImportError:
        return False
    return True


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """Build the small site; return its HTML folder."""
    missing = [m for m in DOCS_PACKAGES if not _installed(m)]
    _need(f"the docs extra ({', '.join(missing)})", not missing)
    _need("the viewer bundle (npm --prefix viewer run build)", viewer_bundle_path().exists())
    mathjax = ROOT / "docs" / "node_modules"
    _need("MathJax (npm --prefix docs ci) or npm", mathjax.is_dir() or shutil.which("npm"))
    top = tmp_path_factory.mktemp("site")
    # conf.py finds the package, the examples and the benchmark results next to
    # docs/: a copy of docs/ beside links to the rest, so that what the build
    # generates (docs/generated, docs/auto_examples, docs/_build) stays here
    shutil.copytree(ROOT / "docs", top / "docs",
                    ignore=shutil.ignore_patterns("_build", "generated", "auto_examples",
                                                  "sg_execution_times.rst", "node_modules"))
    if mathjax.is_dir():           # else conf.py installs MathJax in the copy
        (top / "docs" / "node_modules").symlink_to(mathjax)
    for name in ("geotex", "examples", "benchmarks", "README.md"):
        (top / name).symlink_to(ROOT / name)
    env = dict(os.environ, GEOTEX_EXAMPLES_ONLY=EXAMPLE, GEOTEX_DOCS_API=API_MODULE,
               PYTHONPATH=str(top))
    env.pop("GEOTEX_EXAMPLES_QUICK", None)
    html = top / "docs" / "_build" / "html"
    start = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q",
                        str(top / "docs"), str(html)],
                       capture_output=True, text=True, timeout=900, env=env, cwd=top)
    print(f"sphinx-build of the small site: {time.perf_counter() - start:.1f} s")
    assert p.returncode == 0, (p.stdout + p.stderr)[-4000:]
    return html


def _open(page_path: Path, *, wait_for_viewer: bool, wait_for_math: bool = False):
    """Open a built page; return (canvas screenshot or None, console errors, page facts)."""
    _need("chromium", CHROMIUM is not None)
    with chromium_page((1100, 900)) as (page, errors, failed):
        page.goto(page_path.resolve().as_uri(), wait_until="load")
        shot, state = None, None
        if wait_for_viewer:
            viewer = page.locator(".geotex-viewer").first
            viewer.scroll_into_view_if_needed()
            page.wait_for_selector(".geotex-viewer[data-state=loaded], "
                                   ".geotex-viewer[data-state=error]", timeout=90_000)
            state = viewer.get_attribute("data-state")
            if state == "loaded":
                shot = viewer.locator("canvas").screenshot()
        if wait_for_math:
            page.wait_for_selector("mjx-container svg", state="attached", timeout=60_000)
        facts = page.evaluate("""() => ({
            images: [...document.images].map(i => [i.src, i.complete && i.naturalWidth > 0]),
            scripts: [...document.scripts].filter(s => s.src).map(s => s.src),
            styles: [...document.querySelectorAll('link[rel=stylesheet]')].map(l => l.href),
            links: [...document.querySelectorAll('a[href]')].map(a => a.href),
            viewers: document.querySelectorAll('.geotex-viewer').length,
            math: document.querySelectorAll('mjx-container').length,
            mathSvg: document.querySelectorAll('mjx-container svg').length,
        })""")
        facts["state"] = state
        facts["failed"] = failed
    img = np.asarray(Image.open(io.BytesIO(shot)).convert("RGB")).astype(int) if shot else None
    return img, errors, facts


def _local_file(url: str) -> Path | None:
    u = urlparse(url)
    return Path(unquote(u.path)) if u.scheme == "file" else None


def test_gallery_page_shows_the_model(site, tmp_path):
    page = site / "auto_examples" / f"{EXAMPLE}.html"
    assert page.exists(), sorted(p.name for p in (site / "auto_examples").iterdir())
    img, errors, facts = _open(page, wait_for_viewer=True)
    assert errors == [] and facts["failed"] == []
    assert facts["viewers"] >= 1 and facts["state"] == "loaded"
    Image.fromarray(img.astype(np.uint8)).save(tmp_path / f"{EXAMPLE}.png")
    # the canvas is not blank: a good part differs from the background colour
    background = np.array([0xee, 0xf1, 0xf5])
    model = np.abs(img - background).sum(axis=2) > 40
    assert 0.03 < model.mean() < 0.97, model.mean()
    # the checkerboard texture shows (yellow and blue squares), not a plain colour
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    assert ((r > b + 60) & (g > b + 30)).mean() > 0.01
    assert ((b > r + 50) & (b > g + 20)).mean() > 0.01
    # the example's picture is on the page too
    pictures = [src for src, ok in facts["images"] if EXAMPLE in src]
    assert pictures and all(ok for src, ok in facts["images"])


def test_home_page_loads_without_errors_or_missing_files(site):
    img, errors, facts = _open(site / "index.html", wait_for_viewer=False)
    assert errors == [] and facts["failed"] == []
    broken = [src for src, ok in facts["images"] if not ok]
    assert broken == []
    assert facts["scripts"] and facts["styles"]
    assert facts["images"], "the home page shows a picture"
    outside = [src for src, _ in facts["images"] if _local_file(src) is None]
    assert outside == [], "pictures are part of the site"
    local = [_local_file(u) for u in facts["scripts"] + facts["styles"] + facts["links"]]
    missing = sorted(str(p) for p in local if p is not None and not p.exists())
    assert missing == []
    # the scripts are the site's own (no CDN: the site works offline)
    assert all(_local_file(u) is not None for u in facts["scripts"])
    assert any(_local_file(u).name == "geotex-viewer.js" for u in facts["scripts"])


_TAG = re.compile(r"<(script|link)\b[^>]*>", re.I)
_REMOTE = re.compile(r"\b(src|href)\s*=\s*[\"']?\s*(https?:)?//", re.I)


def _remote_assets(html: str) -> list[str]:
    """Script tags with a network ``src`` and stylesheet links with a network ``href``."""
    tags = (m.group(0) for m in _TAG.finditer(html))
    return [t for t in tags if _REMOTE.search(t)
            and (t[1:7].lower() == "script" or "stylesheet" in t.lower())]


def test_no_page_loads_a_script_from_the_network(site):
    assert _remote_assets('<script defer src="https://cdn.x/mathjax.js"></script>')
    assert _remote_assets("<link rel='stylesheet' href='//cdn.x/a.css'>")
    assert not _remote_assets('<script src="_static/a.js"></script><a href="https://x">')
    pages = sorted(site.rglob("*.html"))
    assert len(pages) > 10
    remote = {str(p.relative_to(site)): _remote_assets(p.read_text()) for p in pages}
    remote = {k: v for k, v in remote.items() if v}
    assert remote == {}, "scripts and styles must come from the site itself (no CDN)"
    # MathJax is one of the site's own files, and the pages with math load it
    assert (site / "_static" / "mathjax" / "tex-svg-full.js").stat().st_size > 500_000
    with_math = [p for p in pages if "_static/mathjax/tex-svg-full.js" in p.read_text()]
    assert any(p.name == "getting-started-researchers.html" for p in with_math)


def test_math_renders_offline(site):
    page = site / "getting-started-researchers.html"
    _, errors, facts = _open(page, wait_for_viewer=False, wait_for_math=True)
    assert errors == [] and facts["failed"] == []
    # $N = 1, 2, 4$ and $z^N$ on that page: typeset by MathJax as SVG
    assert facts["math"] >= 2 and facts["mathSvg"] >= 2
    assert all(_local_file(u) is not None for u in facts["scripts"])
