"""Compiled number text (geotex.io.numtext): equal to repr / %d / float, bit for bit."""

import io
import struct
import zipfile

import numpy as np
import pytest

from geotex.errors import InputError, MeshFileError
from geotex.io import numtext, read_mesh, threemf, write_mesh
from geotex.io.numtext import format_rows, parse_floats, parse_ints, quoted_spans
from geotex.io.threemf import model_xml, read_3mf
from geotex.mesh.record import Mesh


@pytest.fixture(params=["compiled", "python"])
def path(request, monkeypatch):
    """Both paths: compiled loops (any size) and Python (below JIT_MIN_SIZE)."""
    size = 0 if request.param == "compiled" else 10 ** 12
    monkeypatch.setattr(numtext, "JIT_MIN_SIZE", size)
    monkeypatch.setattr(threemf, "JIT_MIN_SIZE", size)
    return request.param


def _values(seed=0, n=60000):
    rng = np.random.default_rng(seed)
    parts = [
        rng.normal(size=n) * 10.0 ** rng.integers(-13, 16, n),        # every magnitude
        rng.normal(size=n).astype(np.float32).astype(np.float64) * 80,  # STL coordinates
        np.round(rng.normal(size=n) * 1e4) / 10.0 ** rng.integers(0, 7, n),  # short decimals
        rng.integers(-10 ** 6, 10 ** 6, n).astype(np.float64),
        np.array([0.0, -0.0, 1e-5, 1e-11, 9.999999999999999e13, 1e14, 1e16, 0.1, 0.3,
                  5e-324, 1e300, 123456789012345.6, 1e-4, 2.0 ** -30, 9.9999999999999995,
                  0.5, 1e13, 99999999999999.99, 2.0 ** 52, 2.0 ** 53 + 2, 4.35, 1 / 3,
                  np.nextafter(1.0, 2), np.nextafter(1.0, 0), np.inf, -np.inf, np.nan]),
    ]
    return np.concatenate(parts)


def test_floats_are_formatted_as_repr(path):
    vals = _values()
    text = format_rows(("", "\n"), vals.reshape(-1, 1))
    assert text == "".join(f"{v!r}\n" for v in vals.tolist()).encode()


def test_rows_of_floats_and_ints_match_percent_formatting(path):
    rng = np.random.default_rng(1)
    V = rng.normal(size=(500, 3)) * 30
    pieces = ('  <vertex x="', '" y="', '" z="', '"/>\n')
    assert format_rows(pieces, V) == "".join(
        '  <vertex x="%r" y="%r" z="%r"/>\n' % tuple(r) for r in V.tolist()).encode()
    Fi = rng.integers(-10 ** 15, 10 ** 15, (500, 3))
    Fi[0, 0] = np.iinfo(np.int64).min
    Fi[1] = [0, 9, 10]
    assert format_rows(("a", ",", ";", "\n"), Fi) == "".join(
        "a%d,%d;%d\n" % tuple(r) for r in Fi.tolist()).encode()
    assert format_rows(("x", "\n"), np.zeros((0, 1))) == b""
    assert format_rows(("%d", "%\n"), V[:1, :1]) == b"%%d%r%%\n" % float(V[0, 0])
    with pytest.raises(InputError):
        format_rows(("a", "b"), V)


def _spans(tokens):
    body = b'"' + b'" "'.join(tokens) + b'"'
    quotes = np.flatnonzero(np.frombuffer(body, np.uint8) == ord('"'))
    return body, quotes[0::2] + 1, quotes[1::2]


def test_parsed_floats_equal_python_float():
    vals = _values(seed=2)
    vals = vals[np.isfinite(vals)]
    tokens = [repr(v).encode() for v in vals.tolist()]
    tokens += [b"1.5e-3", b"+2.25", b"-.5", b"5.", b"1E5", b"0000.000123", b"-0",
               b"9007199254740993",            # 2**53 + 1: a tie, rounds to even
               b"9007199254740995",            # tie, rounds up to even
               b"1.7976931348623157e308", b"2.2250738585072014e-308",
               b"4.9406564584124654e-324",      # subnormal: left to numpy
               b"1234567890123456789", b"0.1234567890123456789",
               b"123456789012345678901",        # 21 digits: left to numpy
               b"1_000", b" 1", b"1e", b"e5", b".", b"--1", b"0x10", b"nan", b"inf"]
    body, starts, ends = _spans(tokens)
    values, handled = parse_floats(body, starts, ends)
    for tok, v, ok in zip(tokens, values.tolist(), handled.tolist()):
        if ok:
            assert struct.pack("<d", v) == struct.pack("<d", float(tok)), tok
    inside = (np.abs(vals) >= 1e-11) & (np.abs(vals) < 1e14)     # repr has <= 27 decimals
    assert handled[:vals.size][inside].all() and handled[:vals.size].mean() > 0.9
    # beyond 1e22 / below 1e-27 after the digits, subnormal, > 19 digits, not a
    # plain decimal: left to numpy
    assert handled[vals.size:].tolist() == [True] * 9 + [False] * 3 + [True] * 2 + [False] * 10


def test_parsed_floats_of_every_float32_value_in_a_range():
    # every float32 between 1 and 1 + 2**-10: all of their 16- and 17-digit reprs
    bits = np.arange(0x3F800000, 0x3F800000 + (1 << 13), dtype=np.uint32)
    vals = bits.view(np.float32).astype(np.float64) * 37.0
    tokens = [repr(v).encode() for v in vals.tolist()]
    body, starts, ends = _spans(tokens)
    values, handled = parse_floats(body, starts, ends)
    assert handled.all() and np.array_equal(values, vals)


def test_parsed_ints():
    tokens = [b"0", b"7", b"0012", b"123456789012345678", b"1234567890123456789", b"-1",
              b"+3", b"", b"1.0"]
    body, starts, ends = _spans(tokens)
    values, handled = parse_ints(body, starts, ends)
    assert values[:4].tolist() == [0, 7, 12, 123456789012345678]
    assert handled.tolist() == [True] * 4 + [False] * 5


def test_quoted_spans_finds_uniform_separators():
    body = b'<v x="1" y="2" z="3"/><v x="4" y="5" z="6"/>'
    quotes, seps = quoted_spans(body, b'"', 3)
    assert quotes.shape == (12,) and seps == [b' y=', b' z=', b'/><v x=']
    _, seps = quoted_spans(body.replace(b'y="5"', b'y ="5"'), b'"', 3)
    assert seps is None


def _mesh(seed=0, n=3000):
    rng = np.random.default_rng(seed)
    V = (rng.normal(size=(n, 3)) * 40).astype(np.float32).astype(np.float64)
    V[0] = [0.0, -0.0, 1e-300]                   # values left to repr / numpy
    V[1] = [1e15, -1e-12, 2.5]
    F = rng.integers(0, n, (2 * n, 3))
    return Mesh(V, F, name="r")


def test_3mf_model_text_is_unchanged_and_reads_back_exactly(path, tmp_path):
    mesh = _mesh()
    xml = model_xml(mesh)
    rows = "".join('     <vertex x="%r" y="%r" z="%r"/>\n' % tuple(r)
                   for r in mesh.vertices.tolist())
    assert rows.encode() in xml
    path = write_mesh(tmp_path / "r.3mf", mesh)
    back = read_mesh(path)
    assert back.vertices.tobytes() == mesh.vertices.tobytes()
    assert np.array_equal(back.faces, mesh.faces)
    assert write_mesh(tmp_path / "s.3mf", mesh).read_bytes() == path.read_bytes()


def _package(model: bytes) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("3D/3dmodel.model", model)
    return buf.getvalue()


def _model(vertices: bytes, triangles: bytes) -> bytes:
    return (b'<?xml version="1.0"?><model unit="millimeter" xmlns="http://schemas.microsoft'
            b'.com/3dmanufacturing/core/2015/02"><resources><object id="1"><mesh><vertices>'
            + vertices + b"</vertices><triangles>" + triangles + b"</triangles></mesh>"
            b'</object></resources><build><item objectid="1"/></build></model>')


def test_3mf_odd_tokens_read_as_before(path):
    # tokens outside the compiled grammar go to numpy, as before: same values
    verts = b"".join(b'<vertex x="%s" y="%s" z="%s"/>' % t for t in
                     [(b"1", b"+2.5", b"1E2"), (b"1_0", b"0.1234567890123456789012", b"-0"),
                      (b".5", b"5.", b"4.9406564584124654e-324")] * 3)
    tris = b"".join(b'<triangle v1="%s" v2="%s" v3="%s"/>' % t for t in
                    [(b"0", b"+1", b"002"), (b"3", b"4", b"5")] * 2)
    mesh = read_3mf("odd.3mf", _package(_model(verts, tris)))
    expect = np.array([[1, 2.5, 100], [10, 0.1234567890123456789012, -0.0],
                       [0.5, 5, 5e-324]] * 3)
    assert mesh.vertices.tobytes() == expect.tobytes()
    assert mesh.faces.tolist() == [[0, 1, 2], [3, 4, 5]] * 2


@pytest.mark.parametrize("bad, what", [(b"1.2.3", "vertex coordinate"),
                                       (b"0x1", "vertex coordinate")])
def test_3mf_bad_token_is_named(path, bad, what):
    verts = b"".join(b'<vertex x="%s" y="0" z="0"/>' % (bad if i == 5 else b"1")
                     for i in range(10))
    tris = b'<triangle v1="0" v2="1" v3="2"/>' * 3
    with pytest.raises(MeshFileError, match=what + ".*" + bad.decode().replace(".", r"\.")):
        read_3mf("bad.3mf", _package(_model(verts, tris)))


def test_3mf_bad_index_is_named(path):
    verts = b'<vertex x="0" y="0" z="0"/>' * 4
    tris = b'<triangle v1="0" v2="1" v3="2"/>' * 3 + b'<triangle v1="0" v2="x1" v3="2"/>'
    with pytest.raises(MeshFileError, match="bad triangle index 'x1'"):
        read_3mf("bad.3mf", _package(_model(verts, tris)))


def test_3mf_huge_index_is_refused(path):
    verts = b'<vertex x="0" y="0" z="0"/>' * 4
    tris = b'<triangle v1="0" v2="1" v3="2"/>' * 3 + b'<triangle v1="0" v2="1" v3="%s"/>' % (
        b"9" * 40)
    with pytest.raises(MeshFileError):
        read_3mf("big.3mf", _package(_model(verts, tris)))


def test_3mf_written_in_pieces_is_the_one_piece_package(path):
    # large meshes are formatted piece by piece in a thread while the pieces
    # before are compressed: the package is byte for byte the one-shot one
    mesh = _mesh(seed=3, n=70000)                     # 210k rows: several pieces
    buf = io.BytesIO()
    threemf.write_3mf(buf, mesh)
    ref = io.BytesIO()
    with zipfile.ZipFile(ref, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        for name, text in (("[Content_Types].xml", threemf._CONTENT_TYPES),
                           ("_rels/.rels", threemf._RELS),
                           ("3D/3dmodel.model", model_xml(mesh))):
            z.writestr(threemf._entry(name), text, compresslevel=1)
    assert buf.getvalue() == ref.getvalue()
    back = read_3mf("p.3mf", buf.getvalue())
    assert back.vertices.tobytes() == mesh.vertices.tobytes()
    assert np.array_equal(back.faces, mesh.faces)
