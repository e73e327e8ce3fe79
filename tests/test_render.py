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


# ---- one up-axis rule, textures, camera (issue 19) ------------------------------------

def _figure():
    """An asymmetric z-up object: a tall box with a ball on top, off to +x."""
    from geotex.mesh.primitives import box, icosphere
    Vb, Fb = box((0.0, 0.0, 0.0), (1.0, 0.6, 2.0), divisions=2)
    Vs, Fs = icosphere(2, radius=0.45, center=(1.1, 0.3, 2.2))
    return np.vstack([Vb, Vs]), np.vstack([Fb, Fs + Vb.shape[0]])


def _mask(path):
    img = np.asarray(Image.open(path).convert("RGB")).astype(int)
    # the background is a white-to-blue-grey gradient; the object is beige and shaded
    return np.abs(img - img[:, :1]).sum(axis=2) > 30, img


def _moments(mask):
    ys, xs = np.nonzero(mask)
    return np.array([xs.mean() / mask.shape[1], ys.mean() / mask.shape[0],
                     xs.std() / mask.shape[1], ys.std() / mask.shape[0]])


def _render_cli(capsys, path, out, *extra):
    from geotex.cli import main
    code = main(["render", str(path), "-o", str(out), "--size", "240", "180",
                 "--title", "", *extra])
    capsys.readouterr()
    assert code == 0
    return out


def test_up_rule_is_the_same_for_every_format(tmp_path, capsys):
    from geotex.io import write_mesh
    from geotex.mesh import Mesh
    V, F = _figure()
    write_mesh(tmp_path / "m.obj", Mesh(V, F))
    write_mesh(tmp_path / "m.stl", Mesh(V, F))
    # the same object in glTF's y-up convention: (x, y, z) -> (x, z, -y)
    write_mesh(tmp_path / "m.glb", Mesh(np.column_stack([V[:, 0], V[:, 2], -V[:, 1]]), F))
    moments = {}
    for name in ("m.obj", "m.stl", "m.glb"):
        mask, _ = _mask(_render_cli(capsys, tmp_path / name, tmp_path / (name + ".png")))
        moments[name] = _moments(mask)
    np.testing.assert_allclose(moments["m.obj"], moments["m.stl"], atol=0.01)
    np.testing.assert_allclose(moments["m.obj"], moments["m.glb"], atol=0.01)
    # upright: the tall object spreads more vertically than horizontally, and the
    # ball on top lies in the upper part of the picture (above the centroid)
    m = moments["m.obj"]
    assert m[3] > m[2]
    # --up y on the z-up STL lies it down: a different picture
    mask, _ = _mask(_render_cli(capsys, tmp_path / "m.stl", tmp_path / "y.png", "--up", "y"))
    assert np.abs(_moments(mask) - m).max() > 0.03


def test_default_view_fills_the_picture_and_looks_from_above(tmp_path):
    from geotex.render import view_direction
    V, F = _figure()
    mask, _ = _mask(render_mesh(V, F, tmp_path / "f.png", size=(240, 180)))
    rows, cols = np.nonzero(mask.any(axis=1))[0], np.nonzero(mask.any(axis=0))[0]
    # the object spans nearly the full height of the picture
    assert rows.max() - rows.min() > 0.8 * mask.shape[0]
    for up in ("x", "y", "z"):
        d = view_direction(up)
        assert d @ np.eye(3)["xyz".index(up)] > 0.3     # from above, never the underside


def test_closeup_looks_at_the_point(tmp_path, capsys):
    from geotex.io import write_mesh
    from geotex.mesh import Mesh
    V, F = _figure()
    write_mesh(tmp_path / "m.stl", Mesh(V, F))
    full, _ = _mask(_render_cli(capsys, tmp_path / "m.stl", tmp_path / "a.png"))
    close, _ = _mask(_render_cli(capsys, tmp_path / "m.stl", tmp_path / "b.png",
                                 "--closeup", "1.1,0.3,2.65,0.3"))
    # the top of the ball seen from close by covers much more of the picture
    assert close.mean() > 1.3 * full.mean()
    from geotex.cli import main
    for bad in ("1,2", "a,b,c", "1,2,3,-1", "1,2,nan"):
        assert main(["render", str(tmp_path / "m.stl"), "-o", str(tmp_path / "c.png"),
                     "--closeup", bad]) == 2
        assert "--closeup" in capsys.readouterr().err
    assert not (tmp_path / "c.png").exists()


def test_textured_glb_and_obj_draw_their_texture(tmp_path, capsys):
    from geotex.io import read_mesh, write_mesh
    from geotex.mesh import Mesh
    from geotex.mesh.primitives import icosphere
    V, F = icosphere(3)
    # per-corner uv: u from the longitude of each corner, v from the height
    P = V[F].reshape(-1, 3)
    uv = np.column_stack([(np.arctan2(P[:, 1], P[:, 0]) / (2 * np.pi)) % 1.0,
                          0.5 + 0.5 * P[:, 2]])
    tex = np.zeros((64, 64, 3), np.uint8)
    tex[:, :32] = (220, 30, 30)          # red left half, green right half
    tex[:, 32:] = (30, 180, 40)
    mesh = Mesh(V, F, uv=uv, uv_faces=np.arange(F.size).reshape(-1, 3), texture=tex)
    for name in ("t.glb", "t.obj"):
        write_mesh(tmp_path / name, mesh)
        assert read_mesh(tmp_path / name).texture is not None
        _, img = _mask(_render_cli(capsys, tmp_path / name, tmp_path / (name + ".png")))
        r, g, b = img[..., 0], img[..., 1], img[..., 2]
        red = (r > g + 60) & (r > b + 60)
        green = (g > r + 40) & (g > b + 40)
        assert red.mean() > 0.03 and green.mean() > 0.03, name
        _, plain = _mask(_render_cli(capsys, tmp_path / name, tmp_path / "p.png",
                                     "--no-texture"))
        r, g, b = plain[..., 0], plain[..., 1], plain[..., 2]
        assert not ((r > g + 60) & (r > b + 60)).any() and not ((g > r + 40) & (g > b + 40)).any()


def test_split_by_uv():
    from geotex.render import split_by_uv
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    F = np.array([[0, 1, 2], [1, 3, 2]])
    uv = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [0.5, 0.5]])
    FT = np.array([[0, 1, 2], [4, 3, 2]])    # vertex 1 has two uv
    V2, F2, uv2 = split_by_uv(V, F, uv, FT)
    assert V2.shape == (5, 3) and uv2.shape == (5, 2)
    np.testing.assert_array_equal(V2[F2], V[F])
    np.testing.assert_array_equal(uv2[F2], uv[FT])
    with pytest.raises(InputError, match="uv_faces"):
        split_by_uv(V, F, uv, FT[:1])


def test_closeup_keeps_its_caption_free(tmp_path):
    from geotex.mesh.primitives import icosphere
    V, F = icosphere(4, radius=30.0)
    top = V[np.argmax(V[:, 2] - V[:, 1])]
    out = render_panels([Panel(V, F, color="#c8a27a", closeup=top, closeup_radius=6.0,
                               title="a close-up\nwith two caption lines")],
                        tmp_path / "c.png", size=(500, 400))
    img = np.asarray(Image.open(out).convert("RGB")).astype(int)
    beige = (img[..., 0] - img[..., 2]) > 40            # the surface (text is grey)
    band = 2 * 26 + 8                                    # the caption's two lines, px
    assert beige[:band].mean() < 0.002                   # nothing of the surface under it
    # the surface fills the rest, but for the inset in the lower right corner
    x0, y0 = _inset_box(500, 400)
    rest = beige[band + 10:].copy()
    rest[y0 - band - 10:, x0:] = True
    assert rest.mean() > 0.95
    assert beige[y0 + 5:-5, x0 + 5:-5].mean() < 0.9      # the inset is not surface
    text = img[:band].sum(axis=2) < 300
    assert text.mean() > 0.01                            # the caption is drawn


# ---- close-ups with an inset marking where (issue 19, item 5) -------------------------

def _inset_box(w, h):
    """Upper left pixel (column, row) of a close-up's inset in a w x h panel."""
    from geotex.render import _INSET_MARGIN, INSET_FRACTION
    iw = round(INSET_FRACTION * w)
    margin = round(_INSET_MARGIN * w)
    return w - margin - iw, h - margin - round(iw * h / w)


def _red(img):
    return (img[..., 0] > 180) & (img[..., 1] < 90) & (img[..., 2] < 90)


def test_closeup_inset_marks_where(tmp_path):
    V, F = _figure()
    w, h = 480, 360
    ball_top, box_foot = (1.1, 0.3, 2.65), (0.5, 0.0, 0.25)
    imgs = []
    for name, point in (("a", ball_top), ("b", box_foot)):
        out = render_mesh(V, F, tmp_path / f"{name}.png", size=(w, h), title="close-up",
                          closeup=point, closeup_radius=0.3)
        imgs.append(np.asarray(Image.open(out).convert("RGB")).astype(int))
    x0, y0 = _inset_box(w, h)
    rows = []
    for img in imgs:
        inset, red = img[y0:, x0:], _red(img)
        # the inset shows the whole object (not background only) and the red marker,
        # and the marker is nowhere else (the object is beige)
        white = (inset > 235).all(axis=2)
        beige = (inset[..., 0] - inset[..., 2]) > 30
        assert 0.03 < beige.mean() < 0.6 and white.mean() > 0.2
        assert red[y0:, x0:].sum() > 20
        assert not red[:y0].any() and not red[:, :x0].any()
        rows.append(np.nonzero(red[y0:, x0:])[0].mean())
    # the ball on top is marked high in the inset, the box's foot low
    assert rows[0] + 0.25 * (h - y0) < rows[1]


def test_closeup_region_stays_clear_of_inset_and_caption(tmp_path):
    from geotex.mesh.primitives import icosphere
    V, F = icosphere(4, radius=30.0)
    p = V[np.argmax(V[:, 0] + V[:, 2] - V[:, 1])]
    # faces within 3 mm of the close-up point magenta, the rest cyan
    near = (np.linalg.norm(V[F].mean(axis=1) - p, axis=1) < 3.0).astype(float)
    w, h = 500, 400
    out = render_panels([Panel(V, F, scalars=near, cmap="cool", closeup=p, closeup_radius=8.0,
                               title="the spot")], tmp_path / "s.png", size=(w, h))
    img = np.asarray(Image.open(out).convert("RGB")).astype(int)
    magenta = (img[..., 0] > 150) & (img[..., 2] > 150) & (img[..., 1] < 110)
    x0, y0 = _inset_box(w, h)
    band = 26 + 16
    spot = magenta.copy()
    spot[y0:, x0:] = False                               # the inset shows the spot small
    ys, xs = np.nonzero(spot)
    assert spot.sum() > 0.02 * w * h                     # the spot is seen from close by
    assert ys.min() > band and xs.max() < x0 - 5         # clear of the caption and the inset
    # centred in the free part left of the inset, between band and bottom
    assert abs(xs.mean() - 0.5 * x0) < 0.06 * w
    assert abs(ys.mean() - 0.5 * (band + h)) < 0.06 * h


def test_no_inset(tmp_path, capsys):
    from geotex.io import write_mesh
    from geotex.mesh import Mesh
    V, F = _figure()
    write_mesh(tmp_path / "m.stl", Mesh(V, F))
    with_inset = np.asarray(Image.open(_render_cli(
        capsys, tmp_path / "m.stl", tmp_path / "a.png", "--closeup", "1.1,0.3,2.65,0.3")))
    plain = np.asarray(Image.open(_render_cli(
        capsys, tmp_path / "m.stl", tmp_path / "b.png", "--closeup", "1.1,0.3,2.65,0.3",
        "--no-inset")))
    assert _red(with_inset.astype(int)).any()
    assert not _red(plain.astype(int)).any()


def test_long_caption_is_broken_between_words_and_stays_in_its_panel(tmp_path, sphere):
    """A caption wider than its panel wraps onto more lines instead of being cut at
    both edges (the benchmark close-ups' titles were)."""
    from geotex.render import _wrapped_title

    title = "cylinder: BumpMesh default resolution (triplanar)"
    out = render_panels([Panel(*sphere, title=title), Panel(*sphere, title="short")],
                        tmp_path / "c.png", size=(320, 320))
    img = np.asarray(Image.open(out).convert("L")).astype(int)
    ink = img[:34] < 120                         # the first caption line's dark pixels
    for panel in (ink[:, :320], ink[:, 320:]):
        cols = np.nonzero(panel.any(axis=0))[0]
        assert cols.size and cols.min() > 2 and cols.max() < 317
    assert _wrapped_title("short", 320) == "short"
    lines = _wrapped_title(title, 320).split("\n")
    assert len(lines) >= 3 and " ".join(lines) == title
    assert _wrapped_title(title, 2000) == title


def test_labelled_parts_offsets_faces_and_broadcasts_labels():
    from geotex.render import labelled_parts

    a = (np.eye(3), np.array([[0, 1, 2]]), 4)
    empty = (np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), 9)
    b = (np.eye(3) + 1.0, np.array([[0, 1, 2], [2, 1, 0]]), np.array([5, 6]))
    V, F, labels = labelled_parts([a, empty, b])
    assert V.shape == (6, 3)
    assert F.tolist() == [[0, 1, 2], [3, 4, 5], [5, 4, 3]]
    assert labels.tolist() == [4, 5, 6]


def test_labelled_panel_refuses_a_label_without_colour():
    from geotex.render import labelled_panel

    V, F = np.eye(3), np.array([[0, 1, 2]])
    panel = labelled_panel(V, F, np.array([7]), palette={7: "#ff0000"}, title="t")
    assert panel.title == "t"
    with pytest.raises(InputError, match="no colour for labels \\[8\\]"):
        labelled_panel(V, F, np.array([8]), palette={7: "#ff0000"})
