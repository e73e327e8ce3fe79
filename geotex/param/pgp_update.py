"""Local update of a periodic global parameterization (material-space textures §2.1).

When the orientation or scale constraints change in one place, only the
*effect area* of the change needs a new solve (:func:`geotex.patches.effect.effect_area`
grows it); everywhere else the periodic functions stay as they were.  The
update works on a submesh only, so its cost follows the area, not the mesh:

* the *recomputed faces* ``C`` are the area, the faces touching its vertices
  (one ring) and the faces the previous parameterization marked singular
  (their dislocations and cones are re-derived, since a file does not store
  them); the *submesh* ``M`` is every face touching a vertex of ``C``, so the
  vertex fans of ``C`` are complete in it;
* on ``M`` the field (the new one in the area, the previous combed arms
  elsewhere) is combed and the corner rotations found
  (:func:`~geotex.param.pgp.periodic_parameterization`'s steps, on ``M``);
* the previous functions are carried into the new vertex frames: outside the
  area the field is unchanged, so a vertex's new axis is its old axis turned
  by a multiple of 90 degrees (the combing may choose another arm), and the
  4-vector is turned with it;
* the vertices all of whose faces lie in the area are solved with the others
  locked (``A_ff X_f = -A_fb X_b``, energy over the area's faces): one sparse
  positive definite factorization per coupled block for small areas, and for
  areas of :data:`LOCAL_MULTILEVEL_VERTICES` free vertices or more the
  two-level scheme of the initial solve (field-transported clusters solved
  directly, then damped Jacobi sweeps), with the same locked border;
* the corner coordinates are extracted on ``M`` (eq. 4) and kept for ``C``.

Faces outside ``C`` keep their coordinates, axes and flags bit for bit; faces
of ``C`` outside the area that are regular before and after keep theirs too
(their functions and arms are unchanged, so the new extraction equals the old
one up to a grid symmetry); the others get the new coordinates, turned into
their unchanged arm's frame.  The area's faces follow the new field.  This is
the paper's local update (it keeps the border instead of re-solving the
eigenproblem everywhere).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from geotex.errors import InputError
from geotex.fields.frames import face_connection
from geotex.fields.singularities import vertex_indices
from geotex.linalg import factor
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import face_areas
from geotex.param.pgp import (_P, CLUSTER_EDGES, SMOOTHING_SWEEPS, PeriodicParameterization,
                              _clusters, _corner_coordinates, _edge_residuals, _edge_slots,
                              _energy, _face_measures, _field_vectors, _prepared,
                              _prolongation, _rotate, _scale_per_vertex, _touching,
                              _transfers, _vanishing)

__all__ = ["updated_parameterization", "LOCAL_MULTILEVEL_VERTICES"]

#: from this many free vertices the locked solve is two-level instead of direct
LOCAL_MULTILEVEL_VERTICES = 2000


def _quarter_turns(old_axes: np.ndarray, new_axes: np.ndarray, normals: np.ndarray
                   ) -> np.ndarray:
    """Multiples of 90 degrees from ``old_axes`` to ``new_axes`` about ``normals``, (k,)."""
    cross = np.einsum("ij,ij->i", normals, np.cross(old_axes, new_axes))
    angle = np.arctan2(cross, np.einsum("ij,ij->i", old_axes, new_axes))
    return np.mod(np.rint(angle / (0.5 * np.pi)).astype(np.int64), 4)


def _blocks(Aff: sp.csr_matrix, rhs: np.ndarray) -> list[np.ndarray]:
    """Unknown indices of the coupled blocks of ``Aff`` (the ``u`` and ``v`` halves couple
    only through odd corner rotations, so the system falls apart into a few blocks)."""
    coo = Aff.tocoo()
    halves = Aff.shape[0] // 2
    H = sp.csr_matrix((np.ones(coo.row.size, np.int8), (coo.row // 2, coo.col // 2)),
                      shape=(halves, halves))
    count, label = connected_components(H, directed=False)
    order = np.argsort(label, kind="stable")
    starts = np.searchsorted(label[order], np.arange(count + 1))
    out = []
    for c in range(count):
        h = order[starts[c]:starts[c + 1]]
        idx = np.stack([2 * h, 2 * h + 1], axis=1).ravel()
        if not np.any(rhs[idx]):
            raise InputError("the effect area touches no vertex outside it; give faces that "
                             "leave part of the mesh locked")
        out.append(idx)
    return out


def _locked_direct(Aff: sp.csr_matrix, rhs: np.ndarray, blocks) -> np.ndarray:
    """Solve ``Aff x = rhs`` with one factorization per block."""
    x = np.zeros(Aff.shape[0])
    for idx in blocks:
        x[idx] = factor(Aff[idx][:, idx].tocsc(), hpd=True,
                        what="updated_parameterization").solve(rhs[idx])
    return x


def _locked_multilevel(Aff: sp.csr_matrix, rhs: np.ndarray, Vf, I, J, T, cell: float
                       ) -> np.ndarray:
    """Two-level solve of ``Aff x = rhs``: the Galerkin problem on field-transported
    clusters of the free vertices, then :data:`~geotex.param.pgp.SMOOTHING_SWEEPS`
    damped Jacobi sweeps (``I, J, T``: transfers between free vertices, local ids)."""
    nf = Vf.shape[0]
    count, label = _clusters(Vf, I, J, nf, cell)
    P = _prolongation(I, J, T, nf, label, count)
    Ac = (P.T @ Aff @ P).tocsr()
    Ac.data[np.abs(Ac.data) < 1e-14 * np.abs(Ac.data).max()] = 0.0
    Ac.eliminate_zeros()
    y = factor(Ac.tocsc(), hpd=True, what="updated_parameterization").solve(P.T @ rhs)
    x = P @ y
    dinv = 1.0 / np.maximum(Aff.diagonal(), 1e-300)
    for _ in range(SMOOTHING_SWEEPS):
        x = x + 0.5 * dinv * (rhs - Aff @ x)
    return x


def _area_mask(faces, m: int) -> np.ndarray:
    area = np.zeros(m, dtype=bool)
    sel = np.asarray(faces)
    if sel.dtype == bool:
        if sel.shape != (m,):
            raise InputError(f"faces as a mask must have shape ({m},), got {sel.shape}")
        area = sel.copy()
    else:
        sel = sel.ravel()
        if sel.size and (sel.dtype.kind not in "iu" or sel.min() < 0 or sel.max() >= m):
            raise InputError(f"faces must be face ids in [0, {m}) or an ({m},) boolean mask")
        area[sel.astype(np.int64)] = True
    if not area.any():
        raise InputError("faces is empty: there is nothing to update")
    return area


def _previous_residual(previous, V, F) -> float:
    """The previous parameterization's seam residual (recomputed when not stored)."""
    value = getattr(previous, "seam_residual", None)
    if value is None:
        value = getattr(previous, "metadata", {}).get("seam_residual")
    if isinstance(value, (int, float)) and np.isfinite(value):
        return float(value)
    conn = face_connection(V, F)
    ok = ~(previous.singular[conn.faces[:, 0]] | previous.singular[conn.faces[:, 1]])
    edges = np.flatnonzero(ok)
    if edges.size == 0:
        return 0.0
    return float(_edge_residuals(previous.coords, conn, _edge_slots(F, conn), edges).max())


def updated_parameterization(V, F, previous, field, *, scale,
                             faces) -> PeriodicParameterization:
    """Re-solve a periodic global parameterization inside an effect area only.

    The work is local to the area and a ring around it (see the module
    docstring); the mesh is checked there only.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        The mesh ``previous`` was computed on.
    previous : PeriodicParameterization or geotex.param.pgp_store.PgpFile
        The parameterization before the change (its ``functions``, ``axes``,
        ``coords``, ``singular`` and ``cones`` are used).
    field : DirectionField or array_like, (m, 3)
        The new orientation; only its faces in ``faces`` are read (outside,
        the field is ``previous.axes``).
    scale : float or array_like, (n,)
        The new tile size (surface units); it should equal the previous one
        at the vertices outside ``faces``.
    faces : array_like of int, or (m,) bool
        The effect area: the faces where the field or the scale changed and
        around them (e.g. :func:`geotex.patches.effect.effect_area` of the
        changed constraints' faces).  Vertices all of whose faces lie in it
        are re-solved; every other vertex keeps its function.

    Returns
    -------
    PeriodicParameterization
        ``seam_residual`` is the largest of the recomputed edges' deviation
        and ``previous``'s residual (the unchanged edges keep theirs);
        ``gradient_error`` and ``distortion`` are over the whole mesh;
        ``eigenvalues`` are ``previous``'s.

    Raises
    ------
    InputError
        Malformed arrays, ``previous`` made for another mesh, an empty area,
        degenerate or inconsistently oriented faces around it, or an area that
        touches no locked vertex in some part (nothing would hold its solution).
    SolverError
        If the area's system cannot be factored.

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> from geotex.param.pgp import periodic_parameterization
    >>> V, F = grid_plane(6, 6)
    >>> p = periodic_parameterization(V, F, np.tile([1.0, 0, 0], (len(F), 1)), scale=0.5)
    >>> q = updated_parameterization(V, F, p, np.tile([1.0, 0, 0], (len(F), 1)), scale=0.5,
    ...                              faces=np.arange(10, 30))
    >>> bool(np.allclose(q.coords, p.coords))
    True
    """
    V, F = as_mesh_arrays(V, F, allow_empty=False)
    n, m = V.shape[0], F.shape[0]
    if previous.functions.shape != (n, 4) or previous.axes.shape != (m, 3):
        raise InputError(f"previous was computed on another mesh ({previous.functions.shape[0]} "
                         f"vertices, {previous.axes.shape[0]} faces; this one has {n}, {m})")
    vectors = _field_vectors(field, m)
    S = _scale_per_vertex(scale, n)
    area = _area_mask(faces, m)
    old_singular = np.asarray(previous.singular, dtype=bool)
    old_axes = np.asarray(previous.axes, dtype=np.float64)

    # recomputed faces C (area, its one ring, previously singular faces) and the
    # submesh M of every face touching a vertex of C (complete fans around C)
    in_area = np.zeros(n, dtype=bool)
    in_area[F[area]] = True
    outside = np.zeros(n, dtype=bool)
    outside[F[~area]] = True
    core = _touching(in_area, F) | old_singular
    core_v = np.zeros(n, dtype=bool)
    core_v[F[core]] = True
    sub = np.flatnonzero(_touching(core_v, F))           # increasing: first corners kept
    verts, Fs = np.unique(F[sub], return_inverse=True)
    Fs = Fs.reshape(-1, 3)
    Vs = V[verts]
    ns = verts.size
    area_s, core_s = area[sub], core[sub]
    conn = face_connection(Vs, Fs)          # checks the submesh's faces and orientation
    st = _prepared(Vs, Fs, conn, np.where(area_s[:, None], vectors[sub], old_axes[sub]),
                   S[verts])

    # previous functions in the new vertex frames (the arm of the first corner's face)
    _, first_corner = np.unique(Fs.ravel(), return_index=True)
    ref = first_corner // 3
    turns = _quarter_turns(old_axes[sub[ref]], st.arms[ref, 0], conn.N[ref])
    X = np.einsum("vab,vb->va", _P[(4 - turns) % 4], previous.functions[verts])
    free_s = in_area[verts] & ~outside[verts]
    fi = np.flatnonzero(free_s)
    if fi.size:
        # the energy of the faces around free vertices: all of them lie in the area
        near = np.flatnonzero(area_s & _touching(free_s, Fs))
        I, J, T = _transfers(Vs, Fs[near], st.k[near], st.arms[near], st.S_face[near])
        A = _energy(I, J, T, st.weight[near], ns)
        idx = (4 * fi[:, None] + np.arange(4)).ravel()
        fixed = np.ones(4 * ns, dtype=bool)
        fixed[idx] = False
        A = A[idx]
        Aff = A[:, idx].tocsr()
        rhs = -(A[:, fixed] @ X.ravel()[fixed])
        blocks = _blocks(Aff, rhs)
        if fi.size >= LOCAL_MULTILEVEL_VERTICES:
            local = np.full(ns, -1, dtype=np.int64)
            local[fi] = np.arange(fi.size)
            both = free_s[I] & free_s[J]
            cell = CLUSTER_EDGES * float(np.linalg.norm(Vs[J] - Vs[I], axis=1).mean())
            x = _locked_multilevel(Aff, rhs, Vs[fi], local[I[both]], local[J[both]], T[both],
                                   cell)
        else:
            x = _locked_direct(Aff, rhs, blocks)
        X[fi] = x.reshape(-1, 4)

    # functions of the whole mesh, each in its vertex's final frame: the area's
    # faces take the new arms, the others keep theirs
    axes = old_axes.copy()
    axes[sub[area_s]] = st.arms[area_s, 0]
    functions = np.array(previous.functions, dtype=np.float64)
    new_frame = area[sub[ref]]
    functions[verts[new_frame]] = X[new_frame]
    areas = face_areas(V, F)
    vmass = np.bincount(F.ravel(), weights=np.repeat(areas / 3.0, 3), minlength=n)
    vanish = _vanishing(functions, vmass)

    # extraction on the submesh; kept for the recomputed faces
    raw, pred, cs, wind = _corner_coordinates(st, X)
    index_s = vertex_indices(Vs, Fs, st.combed.vectors, symmetry=4, connection=conn)
    known = core_v[verts]                                   # complete fans
    cone = np.zeros(n, dtype=bool)
    index = np.zeros(n)
    for v, k in previous.cones:
        if not core_v[v]:
            cone[v], index[v] = True, k
    cone[verts[known]] = np.nan_to_num(index_s[known]) != 0
    index[verts[known]] = np.nan_to_num(index_s[known])
    winds = (wind[:, 0] != 0) | (wind[:, 1] != 0)
    sing_s = winds | _touching(cone[verts], Fs)
    sing_s[conn.faces[st.open_fan].ravel()] = True
    singular = old_singular | _touching(vanish, F)
    singular[sub[core_s]] = sing_s[core_s] | _touching(vanish, F[sub[core_s]])
    sing_s = singular[sub]
    cs[sing_s] = raw[sing_s, :1] + pred[sing_s]             # the field's local map
    # into the final frames: the area's faces are in them already; the others
    # are turned back to their unchanged arm, and keep the previous coordinates
    # when regular before and after, or singular before and after with the
    # same tile size at their corners (the same local map)
    coords = np.array(previous.coords, dtype=np.float64)
    turned = _quarter_turns(old_axes[sub], st.arms[:, 0], conn.N)
    rescaled = (S[F[sub]] != np.asarray(previous.scale)[F[sub]]).any(axis=1)
    renew = core_s & (area_s | (sing_s != old_singular[sub]) | (sing_s & rescaled))
    cs_final = np.where(area_s[:, None, None], cs, _rotate(cs, turned[:, None]))
    coords[sub[renew]] = cs_final[renew]

    # seam residual: recomputed edges here, the unchanged ones as before
    fin = coords[sub]
    ef, eg = conn.faces[:, 0], conn.faces[:, 1]
    edges = np.flatnonzero((core_s[ef] | core_s[eg]) & ~(sing_s[ef] | sing_s[eg]))
    residual = float(_edge_residuals(fin, conn, st.slots, edges).max()) if edges.size else 0.0
    residual = max(residual, _previous_residual(previous, V, F))
    S_face = S[F].mean(axis=1)
    gerr, dist = _face_measures(V, F, coords, axes, S_face, ~singular, areas)

    cv = np.flatnonzero(cone)
    dl = np.flatnonzero(core_s & winds)
    return PeriodicParameterization(
        coords=coords, singular=singular,
        cones=tuple((int(v), float(index[v])) for v in cv),
        dislocations=tuple((int(sub[f]), int(wind[f, 0]), int(wind[f, 1])) for f in dl),
        index_sum=float(np.sum(index[cv])) if cv.size else 0.0,
        seam_residual=residual, gradient_error=gerr, distortion=dist, scale=S,
        eigenvalues=tuple(previous.eigenvalues), functions=functions, axes=axes)

