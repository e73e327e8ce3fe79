"""Mapping a material-space tile over a surface (material-space textures §2-3).

* ``(s, t)`` per face corner: the periodic global parameterization
  (:func:`geotex.param.pgp.periodic_parameterization`) steered by the
  orientation field and the scale field;
* ``m`` per vertex: material constraints interpolated by Laplacian smoothing
  and clamped to ``[0, 1]`` (:func:`geotex.fields.scalar.material_field`);
  without constraints a default ramp along an "up" axis (bottom band locked
  to 0, top band to 1, the rest interpolated the same way);
* **periodicity hiding** (Fig. 14): ``m`` modulated by a smooth random
  function of the position (a sum of random plane waves of a given
  wavelength), so neighbouring repetitions of the tile read different layers;
* **local update** (§2.1): a changed material constraint re-solves ``m``
  only inside its effect area (:func:`geotex.patches.effect.effect_area`),
  every vertex touching a face outside the area locked to its old value;
* **baking**: the ``(s, t, m)`` lookup is baked into a packed texture atlas
  (:func:`geotex.image.atlas.build_atlas`, xatlas).  Glb/obj viewers, slicers
  and DCC tools read 2D textures only (there is no widely supported 3D
  texture in glTF or OBJ), and per-vertex colours would need several vertices
  per tile texel to show the pattern at all, so the atlas is the only
  portable output that keeps the tile's resolution.  Every atlas texel gets
  the trilinear tile colour at its surface point.  In faces the PGP marks
  singular, the colour is the paper's §3 blend: three lookups, each with the
  coordinates seen from one corner (``s_i + <a, x - x_i> / S``, the field's
  arms ``a, b`` and the face's tile size ``S``), weighted by the barycentric
  coordinates.  (The paper applies the blend on the whole 1-ring of an
  invalid vertex; here only on the singular faces.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import distance_transform_edt

from geotex.errors import InputError
from geotex.fields.combing import combed_vectors
from geotex.fields.directions import DirectionField
from geotex.fields.frames import face_frames
from geotex.fields.scalar import material_field
from geotex.image.atlas import Atlas, build_atlas, rasterize_triangles
from geotex.image.material.tile import MaterialTile, sample_tile
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.record import Mesh
from geotex.mesh.topology import compacted, vertex_components
from geotex.options import finite_number, positive_number
from geotex.patches.effect import effect_area

__all__ = ["material_locks", "default_material", "modulated_material", "MaterialUpdate",
           "update_material", "bake_material_texture", "field_arms"]

#: fraction of the height locked at each end by :func:`default_material`
DEFAULT_BAND = 0.05
#: plane waves summed by :func:`modulated_material`
MODULATION_WAVES = 8


def material_locks(V, F, constraints) -> tuple[np.ndarray, np.ndarray]:
    """Locked vertices and values from material constraints.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    constraints : list of dict
        Entries with a ``"material"`` value in ``[0, 1]`` and one of
        ``"vertex"`` (index), ``"face"`` (its three vertices are locked) or
        ``"point"`` (``[x, y, z]``, the nearest vertex), optionally
        ``"radius"`` (every vertex within that distance of the point or of
        the face's centroid is locked too), or ``"stroke"`` (a list of points,
        each locked like a point).  Entries without ``"material"`` are
        ignored (they are orientation / scale constraints).

    Returns
    -------
    vertices : numpy.ndarray, (k,) int64
        Sorted unique.
    values : numpy.ndarray, (k,) float64
        Where entries overlap, the value of the later entry.

    Raises
    ------
    InputError
        On a material value outside ``[0, 1]`` or an entry that names no
        place (naming the entry).
    """
    # lazy: scipy.spatial takes ~0.1 s to import
    from scipy.spatial import cKDTree

    V, F = as_mesh_arrays(V, F)
    if not isinstance(constraints, (list, tuple)):
        raise InputError("constraints must be a list of dicts")
    tree = None
    verts: list[np.ndarray] = []
    vals: list[np.ndarray] = []
    for i, c in enumerate(constraints):
        if not isinstance(c, dict) or "material" not in c:
            continue
        where = f"constraints[{i}]"
        m = finite_number(c["material"], name=f"{where} material")
        if not 0.0 <= m <= 1.0:
            raise InputError(f"{where} material {m:g} lies outside [0, 1]; material values "
                             "run from 0 (first texture) to 1 (second)")
        radius = 0.0 if c.get("radius") is None else positive_number(
            c["radius"], name=f"{where} radius")
        centers = []
        picked = []
        if c.get("vertex") is not None:
            v = c["vertex"]
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not \
                    0 <= int(v) < V.shape[0]:
                raise InputError(f"{where} vertex {v!r} is not a vertex index in "
                                 f"[0, {V.shape[0]})")
            picked.append(np.array([int(v)]))
            centers.append(V[int(v)])
        elif c.get("face") is not None:
            f = c["face"]
            if isinstance(f, bool) or not isinstance(f, (int, np.integer)) or not \
                    0 <= int(f) < F.shape[0]:
                raise InputError(f"{where} face {f!r} is not a face index in [0, {F.shape[0]})")
            picked.append(F[int(f)])
            centers.append(V[F[int(f)]].mean(axis=0))
        elif c.get("point") is not None or c.get("stroke") is not None:
            pts = [c["point"]] if c.get("point") is not None else c["stroke"]
            try:
                P = np.asarray(pts, dtype=np.float64).reshape(-1, 3)
            except (TypeError, ValueError):
                raise InputError(f"{where} point/stroke must hold [x, y, z] triples") from None
            if P.size == 0 or not np.isfinite(P).all():
                raise InputError(f"{where} point/stroke must hold finite [x, y, z] triples")
            if tree is None:
                tree = cKDTree(V)
            _, idx = tree.query(P)
            picked.append(np.asarray(idx, dtype=np.int64))
            centers.extend(P)
        else:
            raise InputError(f"{where} has a material but no 'vertex', 'face', 'point' or "
                             "'stroke' to put it at")
        if radius > 0:
            if tree is None:
                tree = cKDTree(V)
            for p in centers:
                picked.append(np.asarray(tree.query_ball_point(p, radius), dtype=np.int64))
        ids = np.unique(np.concatenate(picked))
        verts.append(ids)
        vals.append(np.full(ids.size, m))
    if not verts:
        return np.zeros(0, np.int64), np.zeros(0)
    allv = np.concatenate(verts)
    allm = np.concatenate(vals)
    # later entries win: keep the last occurrence of every vertex
    rev = allv[::-1]
    uniq, first = np.unique(rev, return_index=True)
    return uniq, allm[::-1][first]


def default_material(V, F, *, up=(0.0, 0.0, 1.0), band: float = DEFAULT_BAND) -> np.ndarray:
    """A material ramp along an axis: bottom band 0, top band 1, harmonic in between.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    up : array_like, (3,), optional
        The axis (need not be unit).
    band : float, optional
        Fraction of the height range locked at each end (in ``(0, 0.5)``).

    Returns
    -------
    numpy.ndarray, (n,) float64
        In ``[0, 1]`` (:func:`geotex.fields.scalar.material_field`).

    Raises
    ------
    InputError
        On a zero axis, a flat mesh along it, or a bad band; as
        :func:`material_field` otherwise.
    """
    V, F = as_mesh_arrays(V, F)
    u = np.asarray(up, dtype=np.float64)
    if u.shape != (3,) or not np.isfinite(u).all() or not np.linalg.norm(u) > 0:
        raise InputError(f"up must be a non-zero 3-vector, got {up!r}")
    b = finite_number(band, name="band")
    if not 0.0 < b < 0.5:
        raise InputError(f"band must lie in (0, 0.5), got {band!r}")
    used = np.unique(F)
    h = V @ (u / np.linalg.norm(u))
    lo, hi = float(h[used].min()), float(h[used].max())
    if not hi > lo:
        raise InputError("the mesh is flat along the up axis; give another --up axis or "
                         "material constraints")
    x = (h - lo) / (hi - lo)
    bottom = used[x[used] <= b]
    top = used[x[used] >= 1.0 - b]
    locked = np.concatenate([bottom, top])
    values = np.concatenate([np.zeros(bottom.size), np.ones(top.size)])
    return _components_safe_material(V, F, locked, values, x)


def _components_safe_material(V, F, locked, values, fallback) -> np.ndarray:
    """material_field, with components lacking a lock locked to the fallback at one vertex."""
    count, labels = vertex_components(F, V.shape[0])
    has = np.zeros(count, bool)
    lab = labels[locked]
    has[lab[lab >= 0]] = True
    extra = []
    for comp in np.flatnonzero(~has):
        extra.append(int(np.flatnonzero(labels == comp)[0]))
    iso = np.flatnonzero(labels < 0)
    ex = np.array(extra + iso.tolist(), dtype=np.int64)
    lv = np.concatenate([locked, ex])
    vv = np.concatenate([values, np.clip(fallback[ex], 0.0, 1.0)])
    return material_field(V, F, lv, vv)


def modulated_material(V, material, *, amplitude: float = 0.5, wavelength: float,
                       seed=None) -> np.ndarray:
    """Material modulated by smooth noise over the surface (periodicity hiding, Fig. 14).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    material : array_like, (n,) float64
        The material field to modulate.
    amplitude : float, optional
        Largest change of ``m`` (the noise spans ``[-amplitude, amplitude]``).
    wavelength : float
        Wavelength of the noise in surface units; a few tile sizes, so
        neighbouring tile repetitions read different layers.
    seed : int, optional
        The random directions and phases.

    Returns
    -------
    numpy.ndarray, (n,) float64
        ``clip(material + amplitude * noise, 0, 1)``.

    Raises
    ------
    InputError
        On a negative amplitude, a non-positive wavelength or a size mismatch.
    """
    V = np.asarray(V, dtype=np.float64)
    m = np.asarray(material, dtype=np.float64)
    if m.shape != (V.shape[0],):
        raise InputError(f"material must have one value per vertex ({V.shape[0]}), got "
                         f"shape {m.shape}")
    a = finite_number(amplitude, name="amplitude")
    if a < 0:
        raise InputError(f"amplitude must be >= 0, got {amplitude!r}")
    lam = positive_number(wavelength, name="wavelength")
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(MODULATION_WAVES, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    k = 2.0 * np.pi / lam * rng.uniform(0.7, 1.3, size=MODULATION_WAVES)
    phase = rng.uniform(0.0, 2.0 * np.pi, size=MODULATION_WAVES)
    noise = np.sin((V @ d.T) * k + phase).sum(axis=1)
    peak = float(np.abs(noise).max()) if noise.size else 0.0
    if peak > 0:
        noise /= peak
    return np.clip(m + a * noise, 0.0, 1.0)


@dataclass(frozen=True, eq=False)
class MaterialUpdate:
    """Result of :func:`update_material`.

    Attributes
    ----------
    material : numpy.ndarray, (n,) float64
        The updated field (equal to the old one outside the effect area).
    faces : numpy.ndarray, (k,) int64
        The effect area.
    free_vertices : numpy.ndarray, (p,) int64
        Vertices that were re-solved.
    """

    material: np.ndarray
    faces: np.ndarray
    free_vertices: np.ndarray


def update_material(V, F, material, locked_vertices, locked_values, *, max_distance=None,
                    budget_area=None, keep_vertices=None, adjacency=None) -> MaterialUpdate:
    """Re-solve the material field only around changed constraints (§2.1).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    material : array_like, (n,) float64
        The current field.
    locked_vertices : array_like, (k,) int64
    locked_values : array_like, (k,) float64
        The new or changed constraints (values in ``[0, 1]``); the faces
        around them seed the effect area.
    max_distance, budget_area : float, optional
        The brush: see :func:`geotex.patches.effect.effect_area` (one is
        required).
    keep_vertices : array_like of int, optional
        Earlier constraint vertices: inside the area they keep their current
        value.
    adjacency : FaceAdjacency, optional
        :func:`geotex.patches.face_adjacency` of the mesh, reused across
        updates.

    Returns
    -------
    MaterialUpdate

    Raises
    ------
    InputError
        On a material array of the wrong size, bad constraints or brush.
    """
    V, F = as_mesh_arrays(V, F)
    n = V.shape[0]
    old = np.asarray(material, dtype=np.float64)
    if old.shape != (n,):
        raise InputError(f"material must have one value per vertex ({n}), got {old.shape}")
    lv = np.asarray(locked_vertices, dtype=np.int64).ravel()
    lval = np.asarray(locked_values, dtype=np.float64).ravel()
    if lv.size == 0 or lv.shape != lval.shape:
        raise InputError("give at least one locked vertex and one value per locked vertex")
    if lv.min() < 0 or lv.max() >= n:
        raise InputError(f"locked_vertices has indices outside [0, {n})")
    if not (np.isfinite(lval).all() and lval.min() >= 0.0 and lval.max() <= 1.0):
        raise InputError("locked_values: material values must lie in [0, 1]")
    vf = np.zeros(n, bool)
    vf[lv] = True
    seeds = np.flatnonzero(vf[F].any(axis=1))
    faces = effect_area(V, F, seeds, max_distance=max_distance, budget_area=budget_area,
                        adjacency=adjacency)
    inside = np.zeros(F.shape[0], bool)
    inside[faces] = True
    touches_out = np.zeros(n, bool)
    touches_out[F[~inside].ravel()] = True
    Vs, Fs, kept = compacted(V, F[faces], return_index=True)
    local = np.full(n, -1, np.int64)
    local[kept] = np.arange(kept.size)
    fixed = touches_out[kept].copy()
    vals = old[kept].copy()
    if keep_vertices is not None:
        kv = np.asarray(keep_vertices, dtype=np.int64).ravel()
        kv = kv[(kv >= 0) & (kv < n)]
        kv = local[kv]
        fixed[kv[kv >= 0]] = True
    ll = local[lv]
    fixed[ll[ll >= 0]] = True
    vals[ll[ll >= 0]] = lval[ll >= 0]
    locked = np.flatnonzero(fixed)
    new_local = material_field(Vs, Fs, locked, vals[locked])
    out = old.copy()
    out[kept] = new_local
    return MaterialUpdate(material=out, faces=faces, free_vertices=kept[~fixed])


def field_arms(V, F, params, field) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The field's combed arms and tile size per face, for the singular blend.

    Returns
    -------
    arm_s, arm_t : numpy.ndarray, (m, 3) float64
        Unit tangent directions of ``s`` and ``t`` in every face.
    size : numpy.ndarray, (m,) float64
        Tile size per face (mean of the vertex scales).
    """
    V, F = as_mesh_arrays(V, F)
    vec = field.vectors if isinstance(field, DirectionField) else np.asarray(field, np.float64)
    a = combed_vectors(V, F, vec, symmetry=4)
    _, _, normals = face_frames(V, F)
    b = np.cross(normals, a)
    return a, b, np.asarray(params.scale, dtype=np.float64)[F].mean(axis=1)


def bake_material_texture(V, F, params, material, tile: MaterialTile, *, field,
                          resolution: int = 2048, padding: int = 2, atlas: Atlas | None = None,
                          name: str = "") -> Mesh:
    """Bake the ``(s, t, m)`` tile lookup into a texture atlas.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    params : PeriodicParameterization
        Of ``(V, F)`` (corner coordinates, singular faces, scale).
    material : array_like, (n,) float64
        ``m`` per vertex (clipped to ``[0, 1]`` when sampling).
    tile : MaterialTile
    field : DirectionField or array_like, (m, 3)
        The orientation field the parameterization was built from (for the
        three-lookup blend in singular faces).
    resolution, padding : int, optional
        Atlas size and chart padding (:func:`geotex.image.atlas.build_atlas`).
    atlas : Atlas, optional
        Reuse an atlas of ``(V, F)``.
    name : str, optional

    Returns
    -------
    geotex.mesh.Mesh
        With ``uv``, ``uv_faces`` and the baked RGB texture; write it with
        :func:`geotex.io.write_mesh` (``.glb`` or ``.obj`` + MTL + PNG).

    Raises
    ------
    InputError
        When the parameterization or the material belong to another mesh.
    """
    V, F = as_mesh_arrays(V, F)
    m_faces = F.shape[0]
    coords = np.asarray(params.coords)
    if coords.shape != (m_faces, 3, 2):
        raise InputError(f"the parameterization has {coords.shape[0]} faces, the mesh "
                         f"{m_faces}: they belong to different meshes")
    mat = np.asarray(material, dtype=np.float64)
    if mat.shape != (V.shape[0],):
        raise InputError(f"material must have one value per vertex ({V.shape[0]}), got "
                         f"shape {mat.shape}")
    at = build_atlas(V, F, resolution=resolution, padding=padding) if atlas is None else atlas
    W, H = at.width, at.height
    Q = at.uv[at.uv_faces]
    tri = np.stack([Q[..., 0] * W, (1.0 - Q[..., 1]) * H], axis=-1)
    texel, face, bary = rasterize_triangles(tri, W, H)
    st = np.einsum("kc,kcd->kd", bary, coords[face])
    mm = np.einsum("kc,kc->k", bary, mat[F[face]])
    rgb = sample_tile(tile, st[:, 0], st[:, 1], mm)
    sing = np.asarray(params.singular, dtype=bool)[face]
    n_sing = int(sing.sum())
    if n_sing:
        a, b, S = field_arms(V, F, params, field)
        fs, bs = face[sing], bary[sing]
        P = np.einsum("kc,kcd->kd", bs, V[F[fs]])
        blend = np.zeros((n_sing, 3))
        for c in range(3):
            d = P - V[F[fs, c]]
            s = coords[fs, c, 0] + np.einsum("kd,kd->k", d, a[fs]) / S[fs]
            t = coords[fs, c, 1] + np.einsum("kd,kd->k", d, b[fs]) / S[fs]
            blend += bs[:, [c]] * sample_tile(tile, s, t, mm[sing])
        rgb[sing] = blend
    img = np.zeros((H * W, 3), np.float32)
    filled = np.zeros(H * W, bool)
    img[texel] = rgb
    filled[texel] = True
    img = img.reshape(H, W, 3)
    if filled.any() and not filled.all():
        _, (iy, ix) = distance_transform_edt(~filled.reshape(H, W), return_indices=True)
        img = img[iy, ix]
    tex = np.clip(np.rint(img), 0, 255).astype(np.uint8)
    return Mesh(V, F, uv=at.uv, uv_faces=at.uv_faces, texture=tex, name=name,
                metadata={"atlas_charts": at.n_charts, "singular_faces": int(
                    np.asarray(params.singular).sum())})
