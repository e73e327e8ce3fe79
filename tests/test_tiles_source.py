"""Strips and interiors cut from a texture quilted from a small exemplar (issue 14, item 2)."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from geotex.cli import main
from geotex.errors import InputError
from geotex.exemplars import exemplar, save_exemplar
from geotex.tiles import build_tileset, check_seams, load_tileset
from geotex.tiles.build import _exemplar_arrays, plan_tileset
from geotex.tiles.catalog import rebuild
from geotex.tiles.source import MIN_SEGMENTS, SOURCE_SIDE, source_side, strips_along
from geotex.tiles.strips import distinct_segments
from geotex.tiles.tileset import save_tileset


def small(size=1.1):
    return exemplar("studs", size=(size, size), seed=0)


def sha(tiles, path):
    save_tileset(path, tiles)
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_distinct_segments_counts_crossing_sets():
    src = _exemplar_arrays(small(0.9))[0]
    assert distinct_segments(src.lo, src.hi, src.size, along=0) == 0   # shorter than a tile
    src = _exemplar_arrays(small(1.1))[0]
    few = distinct_segments(src.lo, src.hi, src.size, along=0)
    big = _exemplar_arrays(exemplar("studs", size=(4.0, 4.0), seed=0))[0]
    many = distinct_segments(big.lo, big.hi, big.size, along=0)
    # 4 studs: at most the 2^4 - 1 non-empty subsets; the catalog's 4 x 4: many more
    assert 1 <= few < MIN_SEGMENTS * 2 <= many
    assert strips_along((2, 3, 1), isotropic=False) == (3, 3)
    assert strips_along((2, 2, 2), isotropic=True) == (2, 0)


def test_small_exemplar_without_room_builds_from_a_quilted_source():
    # 1.1 x 1.1 studs: too few distinct strips for 2 colours along y today
    ex = small(1.1)
    with pytest.raises(InputError, match="distinct edge strips"):
        build_tileset(ex, colors=2, planar=True, interior="paste", quilted_source=False)
    ts = build_tileset(ex, colors=2, planar=True, interior="paste")       # "auto"
    assert len(ts) == 16 and check_seams(ts).ok
    q = ts.metadata["quilted_source"]
    assert q["side"] == SOURCE_SIDE and q["auto"] and q["elements"] > 4 * 4
    assert ts.metadata["recipe"]["quilted_source"] == SOURCE_SIDE


def test_exemplar_shorter_than_a_tile_builds_quilted_tiles():
    ex = small(0.9)
    with pytest.raises(InputError, match="tile length"):
        build_tileset(ex, colors=1, isotropic=True, quilted_source=False)
    ts = build_tileset(ex, colors=1, isotropic=True, interior="quilt", quilted_source=2.5)
    rep = check_seams(ts)
    assert rep.ok and rep.pairs_checked > 0
    assert ts.metadata["quilted_source"]["side"] == 2.5 and not ts.metadata["quilted_source"]["auto"]
    # the frame's strip elements cross the sides: the tile's boundary is not empty
    V, F = ts.tile(0)
    assert ((V[:, 0] == 0.0) | (V[:, 1] == 0.0)).any()


def test_quilted_strips_are_varied():
    # a 1.3 x 1.3 exemplar gives one stud per strip; its quilted source gives more
    ex = small(1.3)
    plain = plan_tileset(ex, colors=2, isotropic=True, interior="paste", quilted_source=False)
    quilted = plan_tileset(ex, colors=2, isotropic=True, interior="paste")
    assert plain.source is None and quilted.source is not None
    assert quilted.plan.src.size == (SOURCE_SIDE, SOURCE_SIDE)
    n_plain = sum(len(st.boxes) for st in plain.strips[0])
    n_quilted = sum(len(st.boxes) for st in quilted.strips[0])
    assert n_quilted > n_plain
    src = quilted.plan.src
    assert distinct_segments(src.lo, src.hi, src.size, along=0) >= MIN_SEGMENTS * 2


def test_quilted_source_is_deterministic_and_rebuilds_from_its_recipe(tmp_path):
    ex = small(1.1)
    a = build_tileset(ex, colors=1, planar=True, interior="paste", seed=5, quilted_source=2.0)
    b = build_tileset(ex, colors=1, planar=True, interior="paste", seed=5, quilted_source=2.0)
    assert sha(a, tmp_path / "a.npz") == sha(b, tmp_path / "b.npz")
    c = build_tileset(ex, colors=1, planar=True, interior="paste", seed=6, quilted_source=2.0)
    assert sha(c, tmp_path / "c.npz") != sha(a, tmp_path / "a.npz")
    r = a.metadata["recipe"]
    table = {"small": {**r, "exemplar": {"name": "studs", "params": dict(ex.params)}}}
    again = rebuild("small", table=table)
    assert again.metadata["recipe"]["quilted_source"] == 2.0
    for i in range(len(a)):
        assert all(np.array_equal(x, y) for x, y in zip(a.tile(i), again.tile(i)))


def test_default_leaves_large_exemplars_alone(tmp_path):
    ex = exemplar("studs", size=(3.0, 3.0), seed=0)
    a = build_tileset(ex, colors=1, isotropic=True, interior="paste", seed=2)
    b = build_tileset(ex, colors=1, isotropic=True, interior="paste", seed=2,
                      quilted_source=False)
    assert "quilted_source" not in a.metadata
    assert "quilted_source" not in a.metadata["recipe"]
    assert sha(a, tmp_path / "a.npz") == sha(b, tmp_path / "b.npz")


def test_quilted_source_option_errors():
    src = _exemplar_arrays(small(1.3))[0]
    args = (src.lo, src.hi, src.size, (2, 0))
    assert source_side("auto", *args) == SOURCE_SIDE
    assert source_side("auto", *args, lattice=True) == 0.0
    assert source_side(False, *args) == 0.0 and source_side(3, *args) == 3.0
    for bad in ("always", 1.5, 20.0, [4.0]):
        with pytest.raises(InputError, match="quilted_source"):
            source_side(bad, *args)
    with pytest.raises(InputError, match="lattice"):
        source_side(True, *args, lattice=True)
    with pytest.raises(InputError, match="periodic"):
        build_tileset(small(1.3), colors=2, isotropic=True, interior="periodic",
                      quilted_source=True)


def test_cli_quilted_source(tmp_path, capsys):
    ex = tmp_path / "small.npz"
    save_exemplar(ex, small(0.9))
    out = tmp_path / "q.npz"
    assert main(["tiles", "build", str(ex), "-o", str(out), "--colors", "1", "--isotropic",
                 "--interior", "paste", "--quilted-source", "2.5"]) == 0
    assert "quilted from the exemplar" in capsys.readouterr().out
    assert load_tileset(out).metadata["recipe"]["quilted_source"] == 2.5
    assert main(["tiles", "build", str(ex), "-o", str(tmp_path / "n.npz"), "--colors", "1",
                 "--isotropic", "--interior", "paste", "--quilted-source", "no"]) == 2
    assert main(["tiles", "build", str(ex), "-o", str(tmp_path / "m.npz"),
                 "--quilted-source", "maybe"]) == 2
    err = capsys.readouterr().err
    assert "--quilted-source maybe" in err
    assert not (tmp_path / "n.npz").exists() and not (tmp_path / "m.npz").exists()
    for side in ("50", "nan", "1"):                   # the flag's range, named as the flag
        assert main(["tiles", "build", str(ex), "-o", str(tmp_path / "r.npz"),
                     "--quilted-source", side]) == 2
        err = capsys.readouterr().err.strip()
        assert err.endswith("a side between 2 and 12 tile units") and f"--quilted-source {side}" in err
        assert "\n" not in err and "quilted_source" not in err
    assert not (tmp_path / "r.npz").exists()


def test_cropped_exemplar_keeps_whole_elements_only():
    ex = exemplar("studs", size=(4.0, 4.0), seed=0)
    c = ex.cropped((1.3, 1.3))
    assert c.size == (1.3, 1.3) and c.params["cropped"] == [1.3, 1.3]
    assert 0 < c.n_elements < ex.n_elements
    assert c.vertices[:, :2].min() >= 0.0 and c.vertices[:, :2].max() <= 1.3
    assert (c.height, c.depth, c.name) == (ex.height, ex.depth, ex.name)
    with pytest.raises(InputError, match="no element"):
        ex.cropped((0.05, 0.05))
    with pytest.raises(InputError, match="positive"):
        ex.cropped((0.0, 1.0))
