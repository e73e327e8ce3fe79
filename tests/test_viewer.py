"""The offline viewer page of ``geotex view``, opened in headless Chromium.

Under CI (``CI`` set) Chromium, playwright and the built viewer bundle are
required (.ci/run installs and builds them); elsewhere the browser test is
skipped when one is missing, like tests/test_slicers.py.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import tempfile

import numpy as np
import pytest
from PIL import Image

from geotex.cli import main
from geotex.io import write_mesh
from geotex.mesh import Mesh
from geotex.mesh.primitives import icosphere, torus
from geotex.viewpage import viewer_bundle_path

UNDER_CI = bool(os.environ.get("CI"))
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--no-first-run", "--disable-quic", "--disable-sync",
         # WebGL without a GPU: ANGLE on SwiftShader, the software rasterizer shipped
         # with Chromium
         "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]


def _need(what: str, ok: bool):
    if ok:
        return
    if UNDER_CI:
        pytest.fail(f"{what} is required under CI (.ci/run installs it)")
    pytest.skip(f"{what} is not available")


def _textured_ball():
    V, F = icosphere(3, radius=10.0)
    P = V[F].reshape(-1, 3)
    uv = np.column_stack([(np.arctan2(P[:, 1], P[:, 0]) / (2 * np.pi)) % 1.0,
                          0.5 + 0.05 * P[:, 1]])   # red above, blue below (y-up)
    tex = np.zeros((32, 32, 3), np.uint8)
    tex[:16] = (220, 30, 30)
    tex[16:] = (30, 160, 220)
    return Mesh(V, F, uv=uv, uv_faces=np.arange(F.size).reshape(-1, 3), texture=tex)


def test_view_writes_a_page_next_to_the_file(tmp_path, capsys):
    _need("the viewer bundle (npm --prefix viewer run build)", viewer_bundle_path().exists())
    V, F = torus(20.0, 7.0, n_major=24, n_minor=12)
    write_mesh(tmp_path / "ring.stl", Mesh(V, F))
    assert main(["view", str(tmp_path / "ring.stl")]) == 0
    page = (tmp_path / "ring.stl.html").read_text()
    assert 'data-up="y"' in page and "GeotexViewer" in page   # embedded turned y-up
    assert "http://" not in page.split("<script>")[0]          # nothing fetched
    write_mesh(tmp_path / "ball.glb", _textured_ball())
    assert main(["view", str(tmp_path / "ball.glb"), "-o", str(tmp_path / "b.html")]) == 0
    assert 'data-up="y"' in (tmp_path / "b.html").read_text()
    capsys.readouterr()
    # errors: never overwrite the input, HTML only, missing file
    assert main(["view", str(tmp_path / "ring.stl"), "-o", str(tmp_path / "ring.stl")]) == 2
    assert main(["view", str(tmp_path / "ring.stl"), "-o", str(tmp_path / "r.png")]) == 2
    assert main(["view", str(tmp_path / "nope.stl")]) == 2
    err = capsys.readouterr().err
    assert err.count("geotex: error:") == 3 and "Traceback" not in err
    assert not (tmp_path / "r.png").exists()


@contextlib.contextmanager
def chromium_page(viewport=(800, 600)):
    """A page of headless Chromium (fresh profile) and the lists its errors go into.

    Yields ``(page, errors, failed)``: console errors and page errors are appended to
    ``errors``, URLs of failed requests to ``failed``. Shared with test_docs_site.
    """
    if not UNDER_CI:                      # under CI a missing playwright is a failure
        pytest.importorskip("playwright")
    from playwright.sync_api import sync_playwright

    errors, failed = [], []
    with tempfile.TemporaryDirectory() as profile, sync_playwright() as p:
        browser = p.chromium.launch_persistent_context(
            profile, executable_path=CHROMIUM, headless=True, args=FLAGS,
            viewport={"width": viewport[0], "height": viewport[1]})
        try:
            page = browser.new_page()
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.on("requestfailed", lambda r: failed.append(r.url))
            yield page, errors, failed
        finally:
            browser.close()


def _open_in_chromium(page_path):
    """Return (canvas screenshot as array, console errors, element state) for a page."""
    with chromium_page() as (page, errors, _):
        page.goto(page_path.resolve().as_uri())
        page.wait_for_selector(".geotex-viewer[data-state=loaded], "
                               ".geotex-viewer[data-state=error]", timeout=60_000)
        state = page.get_attribute(".geotex-viewer", "data-state")
        shot = page.locator(".geotex-viewer canvas").screenshot() if state == "loaded" else b""
    img = np.asarray(Image.open(io.BytesIO(shot)).convert("RGB")).astype(int) if shot else None
    return img, errors, state


@pytest.mark.parametrize("name", ["ring.stl", "ball.glb"])
def test_page_shows_the_model_in_headless_chromium(tmp_path, capsys, name):
    _need("chromium", CHROMIUM is not None)
    _need("the viewer bundle (npm --prefix viewer run build)", viewer_bundle_path().exists())
    if name == "ring.stl":
        V, F = torus(20.0, 7.0, n_major=24, n_minor=12)
        write_mesh(tmp_path / name, Mesh(V, F))
    else:
        write_mesh(tmp_path / name, _textured_ball())
    assert main(["view", str(tmp_path / name)]) == 0
    capsys.readouterr()
    img, errors, state = _open_in_chromium(tmp_path / (name + ".html"))
    assert errors == [] and state == "loaded"
    Image.fromarray(img.astype(np.uint8)).save(tmp_path / (name + ".png"))
    # the canvas is not blank: a good part differs from the background colour
    background = np.array([0xee, 0xf1, 0xf5])
    model = np.abs(img - background).sum(axis=2) > 40
    assert 0.05 < model.mean() < 0.95
    if name == "ball.glb":        # the texture shows: red and blue, not the plain beige
        r, g, b = img[..., 0], img[..., 1], img[..., 2]
        assert ((r > g + 60) & (r > b + 60)).mean() > 0.02
        assert ((b > r + 60) & (b > g + 20)).mean() > 0.02
