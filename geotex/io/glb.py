"""GLB (binary glTF 2.0) writing, and reading of simple GLB files.

Writing
    One mesh with one triangle primitive: ``POSITION`` (float32 VEC3 with the
    ``min`` / ``max`` the specification requires) and ``indices`` (uint32
    SCALAR).  With uv, ``TEXCOORD_0`` is added; glTF needs one uv per vertex,
    so a vertex used with several uv is split into one vertex per distinct
    (vertex, uv) pair (numbered in order of first appearance in the faces)
    and unreferenced vertices are dropped.  glTF puts the uv origin at the
    top left of the image, so ``(u, 1 - v)`` is stored.  With a texture (and
    uv), the image is embedded as PNG with a sampler, a texture and a
    ``pbrMetallicRoughness.baseColorTexture`` material; otherwise a plain
    light-grey non-metallic material is used.  No normals are written:
    viewers then shade flat, as the specification requires.  Coordinates are
    written as they are, without conversion to glTF's Y-up metres (a Z-up
    millimetre model shows lying on its back in a Y-up viewer, at the scale
    of a building unless the viewer rescales).  A mesh without faces is
    written as a point primitive, an empty mesh as a scene with an empty node.
    Chunks are 4-byte aligned: the JSON is padded with spaces, the binary
    chunk with zeros.  Positions are float32: a round trip is exact only for
    float32-representable coordinates.

Reading
    Every primitive of every mesh in ``meshes`` is read once, in its own
    coordinates: node transforms, instancing and the scene graph are ignored.
    Primitives may be triangles, triangle strips or fans (converted to
    triangles) or points and lines (vertices only); indices may be uint8,
    uint16 or uint32; positions float32 (or any accessor type).  Buffers come
    from the GLB binary chunk, ``data:`` URIs or files next to the GLB: an
    external ``uri`` must be a relative reference to a regular file inside
    the GLB's folder, read up to the declared ``byteLength`` (absolute
    paths, ``..``, other schemes and links leading out are refused, see
    :mod:`geotex.io.limits`).  uv is
    kept (``uv_faces == faces``, ``v`` flipped back) when every primitive has
    ``TEXCOORD_0``; the base colour texture is loaded when all primitives
    share one image.  Sparse accessors and Draco / meshopt compression are not
    supported.
"""

from __future__ import annotations

import base64
import json
import struct

import numpy as np

from geotex.version import VERSION
from geotex.errors import MeshFileError
from geotex.io._common import build_mesh
from geotex.io.images import load_texture_image, texture_to_png_bytes
from geotex.io.limits import (MAX_SIDECAR_BYTES, RefusedInput, human_bytes, read_bounded,
                              sidecar_file)

__all__ = ["read_glb", "write_glb", "glb_document"]

_MAGIC = b"glTF"
_JSON = 0x4E4F534A
_BIN = 0x004E4942
_COMPONENTS = {5120: "i1", 5121: "u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_GEOMETRY_EXTENSIONS = ("KHR_draco_mesh_compression", "EXT_meshopt_compression")
_MAX_ZERO_ACCESSOR = 1 << 24     # elements of an accessor without a bufferView
_MAX_STRIDE = 1 << 16
_ARRAY_BUFFER = 34962
_ELEMENT_ARRAY_BUFFER = 34963


# --------------------------------------------------------------------------- writing


def _split_by_uv(mesh):
    """Per-vertex positions, uv and faces: one vertex per distinct (vertex, uv)."""
    F, FT = mesh.faces, mesh.uv_faces
    key = F.ravel() * np.int64(mesh.uv.shape[0]) + FT.ravel()
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    new_id = np.empty_like(order)
    new_id[order] = np.arange(order.shape[0])
    corners = first[order]
    positions = mesh.vertices[F.ravel()[corners]]
    uv = mesh.uv[FT.ravel()[corners]]
    return positions, uv, new_id[inverse.ravel()].reshape(-1, 3)


class _BinaryBuilder:
    def __init__(self):
        self.data = bytearray()
        self.views = []

    def add(self, payload: bytes, target=None) -> int:
        self.data.extend(b"\x00" * (-len(self.data) % 4))
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(payload)}
        if target is not None:
            view["target"] = target
        self.data.extend(payload)
        self.views.append(view)
        return len(self.views) - 1


def glb_document(mesh, *, path="GLB output") -> tuple[dict, bytes]:
    """Build the glTF JSON document and binary buffer for ``mesh``.

    Returns
    -------
    document : dict
    binary : bytes
        Unpadded binary buffer.

    Raises
    ------
    MeshFileError
        If a coordinate exceeds the float32 range or there are more than
        2**32 - 1 vertices.
    """
    name = mesh.name or "geotex"
    if mesh.uv is not None and mesh.n_faces:
        positions, uv, faces = _split_by_uv(mesh)
    else:
        positions, uv, faces = mesh.vertices, None, mesh.faces
    if positions.size and np.abs(positions).max() > np.finfo(np.float32).max:
        raise MeshFileError(path, "coordinates exceed the float32 range of glTF")
    if positions.shape[0] > np.iinfo(np.uint32).max:
        raise MeshFileError(path, "too many vertices for 32-bit glTF indices")
    doc = {
        "asset": {"version": "2.0", "generator": f"geotex {VERSION}"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": name}],
    }
    if positions.shape[0] == 0:
        return doc, b""
    builder = _BinaryBuilder()
    pos32 = np.ascontiguousarray(positions, dtype="<f4")
    accessors = [{
        "bufferView": builder.add(pos32.tobytes(), _ARRAY_BUFFER),
        "componentType": 5126, "count": int(pos32.shape[0]), "type": "VEC3",
        "min": pos32.min(axis=0).astype(float).tolist(),
        "max": pos32.max(axis=0).astype(float).tolist(),
    }]
    attributes = {"POSITION": 0}
    if uv is not None:
        tex = np.empty((uv.shape[0], 2), dtype="<f4")
        tex[:, 0] = uv[:, 0]
        tex[:, 1] = 1.0 - uv[:, 1]
        accessors.append({
            "bufferView": builder.add(tex.tobytes(), _ARRAY_BUFFER),
            "componentType": 5126, "count": int(tex.shape[0]), "type": "VEC2"})
        attributes["TEXCOORD_0"] = 1
    primitive = {"attributes": attributes, "material": 0}
    if faces.shape[0]:
        idx = np.ascontiguousarray(faces, dtype="<u4").ravel()
        accessors.append({
            "bufferView": builder.add(idx.tobytes(), _ELEMENT_ARRAY_BUFFER),
            "componentType": 5125, "count": int(idx.shape[0]), "type": "SCALAR"})
        primitive["indices"] = len(accessors) - 1
        primitive["mode"] = 4
    else:
        primitive["mode"] = 0
    if mesh.texture is not None and uv is not None:
        image_view = builder.add(texture_to_png_bytes(mesh.texture))
        doc["images"] = [{"bufferView": image_view, "mimeType": "image/png"}]
        doc["samplers"] = [{"magFilter": 9729, "minFilter": 9987,
                            "wrapS": 10497, "wrapT": 10497}]
        doc["textures"] = [{"sampler": 0, "source": 0}]
        doc["materials"] = [{"name": "texture", "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0}, "metallicFactor": 0.0,
            "roughnessFactor": 1.0}}]
    else:
        doc["materials"] = [{"name": "plain", "pbrMetallicRoughness": {
            "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0,
            "roughnessFactor": 0.9}}]
    doc["meshes"] = [{"name": name, "primitives": [primitive]}]
    doc["nodes"][0]["mesh"] = 0
    doc["accessors"] = accessors
    doc["bufferViews"] = builder.views
    doc["buffers"] = [{"byteLength": len(builder.data)}]
    return doc, bytes(builder.data)


def write_glb(fh, mesh, *, path="GLB output", binary: bool = True) -> None:
    """Write ``mesh`` as GLB to the open binary file ``fh`` (see module notes)."""
    doc, binary_data = glb_document(mesh, path=path)
    text = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 4)
    chunks = struct.pack("<II", len(text), _JSON) + text
    if binary_data:
        padded = binary_data + b"\x00" * (-len(binary_data) % 4)
        chunks += struct.pack("<II", len(padded), _BIN) + padded
    fh.write(struct.pack("<4sII", _MAGIC, 2, 12 + len(chunks)))
    fh.write(chunks)


# --------------------------------------------------------------------------- reading


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


class _GLBReader:
    def __init__(self, path, doc: dict, bin_chunk: bytes | None):
        self.path = path
        self.doc = doc
        self.bin_chunk = bin_chunk
        self.buffers: dict[int, bytes] = {}

    def fail(self, message):
        raise MeshFileError(self.path, f"GLB: {message}")

    def item(self, kind: str, index):
        items = self.doc.get(kind)
        if not _is_int(index) or not isinstance(items, list) \
                or not 0 <= index < len(items) or not isinstance(items[index], dict):
            self.fail(f"{kind}[{index}] does not exist")
        return items[index]

    def _uri_bytes(self, uri, what: str, declared: int | None = None) -> bytes:
        """Bytes behind a buffer or image ``uri`` (see :mod:`geotex.io.limits`)."""
        if not isinstance(uri, str):
            self.fail(f"{what} uri must be a string, got {type(uri).__name__}")
        if uri.startswith("data:"):
            head, _, payload = uri.partition(",")
            if not head.endswith(";base64"):
                self.fail(f"{what}: only base64 data URIs are supported")
            if declared is not None and len(payload) > 4 * (declared // 3 + 1) + 4:
                self.fail(f"{what} data URI holds more than the {declared} bytes declared")
            try:
                return base64.b64decode(payload, validate=True)
            except ValueError:
                self.fail(f"{what}: malformed base64 data URI")
        try:
            target = sidecar_file(self.path, uri, what=what, uri=True)
            if declared is not None:
                return read_bounded(target, declared, what=f"{what} {uri[:60]!r}",
                                    exact=True)
            return read_bounded(target, MAX_SIDECAR_BYTES, what=f"{what} {uri[:60]!r}")
        except RefusedInput as exc:
            self.fail(str(exc))

    def buffer(self, index) -> bytes:
        if not _is_int(index):
            self.fail(f"buffers[{index!r}] does not exist")
        if index not in self.buffers:
            spec = self.item("buffers", index)
            length = spec.get("byteLength")
            if not _is_int(length) or length < 0:
                self.fail(f"buffers[{index}] byteLength {length!r} is not a non-negative "
                          "integer")
            if "uri" in spec:
                if length > MAX_SIDECAR_BYTES:
                    self.fail(f"buffers[{index}] byteLength {length} is more than the "
                              f"{human_bytes(MAX_SIDECAR_BYTES)} allowed")
                data = self._uri_bytes(spec["uri"], f"buffers[{index}]", length)
            else:
                if self.bin_chunk is None:
                    self.fail(f"buffers[{index}] refers to the binary chunk, which is "
                              "missing")
                data = self.bin_chunk
            if length > len(data):
                self.fail(f"buffers[{index}] byteLength {length!r} exceeds the "
                          f"{len(data)} bytes available")
            self.buffers[index] = data[:length]
        return self.buffers[index]

    def view_bytes(self, index) -> tuple[bytes, int, int, int | None]:
        view = self.item("bufferViews", index)
        data = self.buffer(view.get("buffer"))
        offset = view.get("byteOffset", 0)
        length = view.get("byteLength")
        if not _is_int(offset) or not _is_int(length) or offset < 0 \
                or length < 0 or offset + length > len(data):
            self.fail(f"bufferViews[{index}] (offset {offset!r}, length {length!r}) lies "
                      f"outside its {len(data)}-byte buffer")
        stride = view.get("byteStride")
        if stride is not None and (not _is_int(stride) or not 0 < stride <= _MAX_STRIDE):
            self.fail(f"bufferViews[{index}] byteStride {stride!r} is not a positive "
                      f"integer up to {_MAX_STRIDE}")
        return data, offset, length, stride

    def accessor(self, index) -> np.ndarray:
        acc = self.item("accessors", index)
        if "sparse" in acc:
            self.fail(f"accessors[{index}] is sparse, which is not supported")
        ctype = acc.get("componentType")
        ctype = _COMPONENTS.get(ctype) if _is_int(ctype) else None
        kind = acc.get("type")
        width = _WIDTH.get(kind) if isinstance(kind, str) else None
        count = acc.get("count")
        if ctype is None or width is None or not _is_int(count) or count < 0:
            self.fail(f"accessors[{index}] has a bad componentType, type or count")
        dt = np.dtype(ctype)
        if "bufferView" not in acc:
            if count > _MAX_ZERO_ACCESSOR:
                self.fail(f"accessors[{index}] has no bufferView and a count of {count}, "
                          f"more than the {_MAX_ZERO_ACCESSOR} allowed")
            return np.zeros((count, width), dtype=dt)
        data, start, length, stride = self.view_bytes(acc["bufferView"])
        offset = acc.get("byteOffset", 0)
        element = dt.itemsize * width
        stride = stride or element
        if not _is_int(offset) or not _is_int(stride) or offset < 0 \
                or stride < element:
            self.fail(f"accessors[{index}] has a bad byteOffset or byteStride")
        need = offset + (stride * (count - 1) + element if count else 0)
        if need > length:
            self.fail(f"accessors[{index}] needs {need} bytes but its bufferView has "
                      f"{length}")
        if count == 0:
            return np.zeros((0, width), dtype=dt)
        arr = np.ndarray((count, width), dtype=dt, buffer=data, offset=start + offset,
                         strides=(stride, dt.itemsize))
        out = arr.astype(dt.newbyteorder("="))
        if acc.get("normalized") and dt.kind in "iu":
            out = out / float(np.iinfo(dt).max)
        return out

    def image(self, texture_index):
        texture = self.item("textures", texture_index)
        source = texture.get("source")
        if source is None:
            return None, None
        spec = self.item("images", source)
        if "bufferView" in spec:
            data, start, length, _ = self.view_bytes(spec["bufferView"])
            payload = data[start:start + length]
        elif "uri" in spec:
            payload = self._uri_bytes(spec["uri"], f"images[{source}]")
        else:
            return source, None
        import io
        return source, load_texture_image(io.BytesIO(payload))


def _primitive_faces(reader, prim, n_vertices, where):
    mode = prim.get("mode", 4)
    if "indices" in prim:
        idx = reader.accessor(prim["indices"])
        if idx.shape[1] != 1 or idx.dtype.kind != "u":
            reader.fail(f"{where}: indices must be an unsigned integer SCALAR accessor")
        idx = idx.ravel().astype(np.int64)
    else:
        idx = np.arange(n_vertices, dtype=np.int64)
    if not _is_int(mode):
        reader.fail(f"{where}: primitive mode {mode!r} is not an integer")
    if mode == 4:
        if idx.shape[0] % 3:
            reader.fail(f"{where}: {idx.shape[0]} triangle indices is not a multiple of 3")
        return idx.reshape(-1, 3)
    if mode in (5, 6):
        t = max(idx.shape[0] - 2, 0)
        i = np.arange(t)
        if mode == 5:
            odd = (i % 2).astype(bool)
            a = np.where(odd, idx[i + 1], idx[i])
            b = np.where(odd, idx[i], idx[i + 1])
            return np.stack([a, b, idx[i + 2]], axis=1)
        return np.stack([np.full(t, idx[0] if t else 0), idx[i + 1], idx[i + 2]], axis=1)
    if mode in (0, 1, 2, 3):
        return np.zeros((0, 3), dtype=np.int64)
    reader.fail(f"{where}: unknown primitive mode {mode!r}")


def read_glb(path, data: bytes):
    """Parse GLB bytes into a :class:`~geotex.mesh.Mesh` (see module notes).

    Raises
    ------
    MeshFileError
        On a bad magic, version or length, malformed chunks or JSON, or
        accessors / buffer views outside their buffers.
    """
    if len(data) < 12:
        raise MeshFileError(path, f"not a GLB file: {len(data)} bytes is shorter than "
                                  "the 12-byte GLB header")
    magic, version, length = struct.unpack_from("<4sII", data)
    if magic != _MAGIC:
        raise MeshFileError(path, f"not a GLB file: bad magic {magic!r} (expected b'glTF')")
    if version != 2:
        raise MeshFileError(path, f"GLB version {version} is not supported (only 2)")
    if length != len(data):
        what = "truncated" if length > len(data) else "damaged"
        raise MeshFileError(path, f"GLB is {what}: the header announces {length} bytes "
                                  f"but the file has {len(data)}")
    chunks = []
    pos = 12
    while pos < length:
        if pos + 8 > length:
            raise MeshFileError(path, f"GLB is damaged: incomplete chunk header at byte {pos}")
        clen, ctype = struct.unpack_from("<II", data, pos)
        if pos + 8 + clen > length:
            raise MeshFileError(path, f"GLB is truncated: chunk at byte {pos} announces "
                                      f"{clen} bytes, only {length - pos - 8} remain")
        chunks.append((ctype, data[pos + 8:pos + 8 + clen]))
        pos += 8 + clen
    if not chunks or chunks[0][0] != _JSON:
        raise MeshFileError(path, "GLB is damaged: the first chunk is not JSON")
    try:
        doc = json.loads(chunks[0][1].decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise MeshFileError(path, f"GLB has malformed JSON: {exc}") from None
    except RecursionError:
        raise MeshFileError(path, "GLB JSON is nested too deeply to be a glTF "
                                  "document") from None
    if not isinstance(doc, dict):
        raise MeshFileError(path, "GLB JSON is not an object")
    version_str = str(doc.get("asset", {}).get("version", "")) if isinstance(
        doc.get("asset"), dict) else ""
    if not version_str.startswith("2"):
        raise MeshFileError(path, f"glTF asset version {version_str!r} is not supported "
                                  "(only 2.x)")
    required = doc.get("extensionsRequired", []) or []
    if not isinstance(required, list):
        raise MeshFileError(path, "GLB 'extensionsRequired' is not a list")
    for ext in required:
        if ext in _GEOMETRY_EXTENSIONS:
            raise MeshFileError(path, f"GLB requires the unsupported extension {ext!r} "
                                      "(compressed geometry)")
    bin_chunk = next((c for t, c in chunks[1:] if t == _BIN), None)
    reader = _GLBReader(path, doc, bin_chunk)
    Vs, Fs, UVs = [], [], []
    materials = set()
    offset = 0
    meshes = doc.get("meshes", []) or []
    if not isinstance(meshes, list):
        raise MeshFileError(path, "GLB 'meshes' is not a list")
    for mi, mesh_spec in enumerate(meshes):
        prims = mesh_spec.get("primitives", []) if isinstance(mesh_spec, dict) else None
        if not isinstance(prims, list):
            reader.fail(f"meshes[{mi}] has no primitives list")
        for pi, prim in enumerate(prims):
            where = f"meshes[{mi}].primitives[{pi}]"
            attrs = prim.get("attributes") if isinstance(prim, dict) else None
            if not isinstance(attrs, dict) or "POSITION" not in attrs:
                reader.fail(f"{where} has no POSITION attribute")
            P = reader.accessor(attrs["POSITION"])
            if P.shape[1] != 3:
                reader.fail(f"{where}: POSITION must be VEC3")
            F = _primitive_faces(reader, prim, P.shape[0], where)
            if F.size and (F.max() >= P.shape[0]):
                reader.fail(f"{where}: index {int(F.max())} out of range ({P.shape[0]} "
                            "vertices)")
            uv = None
            if "TEXCOORD_0" in attrs:
                uv = reader.accessor(attrs["TEXCOORD_0"]).astype(np.float64)
                if uv.shape != (P.shape[0], 2):
                    reader.fail(f"{where}: TEXCOORD_0 must be VEC2 with one row per vertex")
                uv[:, 1] = 1.0 - uv[:, 1]
            material = prim.get("material")
            if material is not None and not _is_int(material):
                reader.fail(f"{where}: material {material!r} is not an index")
            materials.add(material)
            Vs.append(P.astype(np.float64))
            Fs.append(F + offset)
            UVs.append(uv)
            offset += P.shape[0]
    V = np.concatenate(Vs) if Vs else np.zeros((0, 3))
    F = np.concatenate(Fs) if Fs else np.zeros((0, 3), dtype=np.int64)
    uv = np.concatenate(UVs) if UVs and all(u is not None for u in UVs) else None
    texture = None
    meta = {}
    if uv is not None and len(materials) == 1 and None not in materials:
        material = reader.item("materials", next(iter(materials)))
        pbr = material.get("pbrMetallicRoughness")
        base = pbr.get("baseColorTexture") if isinstance(pbr, dict) else None
        if isinstance(base, dict) and "index" in base:
            try:
                _, texture = reader.image(base["index"])
            except MeshFileError:
                raise
            except Exception as exc:  # pillow raises many types for bad images
                meta["texture_warning"] = f"embedded texture unreadable: {type(exc).__name__}"
    return build_mesh(path, V, F, fmt="glb", uv=uv, uv_faces=F if uv is not None else None,
                      texture=texture, metadata=meta)
