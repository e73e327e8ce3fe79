import numpy as np
import pytest
from PIL import Image

from geotex.errors import InputError
from geotex.mesh.primitives import torus
from geotex.render import Panel, render_mesh, render_panels


def test_render_writes_a_nonblank_png(tmp_path, ring):
    V, F = ring
    out = render_mesh(V, F, tmp_path / "t.png", size=(320, 240), title="torus")
    img = np.asarray(Image.open(out).convert("RGB"))
    assert img.shape == (240, 320, 3)
    # the mesh covers a good part of the picture and is not background-coloured
    corner = img[0, 0].astype(int)
    differs = np.abs(img.astype(int) - corner).sum(axis=2) > 40
    assert 0.1 < differs.mean() < 0.9
    assert list(tmp_path.iterdir()) == [out]


def test_panels_side_by_side(tmp_path, ring, sphere):
    out = render_panels([Panel(*ring, title="a"), Panel(*sphere, color="#88aaee",
                                                       highlight={"edges": [[0, 1], [1, 2]]})],
                        tmp_path / "p.png", size=(200, 150))
    assert Image.open(out).size == (400, 150)


def test_render_errors(tmp_path, ring):
    with pytest.raises(InputError, match="PNG"):
        render_mesh(*ring, tmp_path / "x.jpg")
    with pytest.raises(InputError, match="up must be"):
        render_mesh(*ring, tmp_path / "x.png", up="w")
    with pytest.raises(InputError, match="nothing to render"):
        render_panels([], tmp_path / "x.png")
    assert not list(tmp_path.iterdir())


def test_arrows_markers_and_texture(tmp_path, sphere):
    V, F = sphere
    C = V[F].mean(axis=1)
    tex = (np.indices((64, 64)).sum(0) // 8 % 2 * 200 + 30).astype(np.uint8)
    tex = np.repeat(tex[:, :, None], 3, axis=2)
    out = render_panels([
        Panel(V, F, arrows=(C[:50], np.tile([0.0, 0.0, 0.2], (50, 1))),
              markers={"poles": ([[0, 0, 1], [0, 0, -1]], "#e4202a")}),
        Panel(V, F, uv=V[:, :2], texture=tex)], tmp_path / "a.png", size=(200, 150))
    img = np.asarray(Image.open(out).convert("RGB")).astype(int)
    red = (img[..., 0] > 180) & (img[..., 1] < 90) & (img[..., 2] < 90)
    assert red[:, :200].any()            # the marker (and its legend) is drawn
    right = img[:, 200:]
    assert right.std() > 30               # the checkerboard shows contrast
    with pytest.raises(InputError, match="uv and texture"):
        Panel(V, F, uv=V[:, :2])
