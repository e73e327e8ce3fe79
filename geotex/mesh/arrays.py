"""Conversion and validation of vertex and face arrays at the public boundary."""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError

__all__ = ["as_vertices", "as_faces", "as_mesh_arrays", "mesh_digest"]


def as_vertices(V, *, name: str = "V", allow_empty: bool = True) -> np.ndarray:
    """Return ``V`` as a C-contiguous ``(n, 3)`` float64 array of finite values.

    Parameters
    ----------
    V : array_like, (n, 3)
        Vertex positions.
    name : str, optional
        Argument name used in error messages.
    allow_empty : bool, optional
        Accept ``n == 0``.

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        A new array when a conversion was needed, otherwise ``V`` itself
        (callers never modify it).

    Raises
    ------
    InputError
        If the shape is not ``(n, 3)``, values are not finite, or the array is
        empty while ``allow_empty`` is false.
    """
    try:
        arr = np.ascontiguousarray(V, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a numeric (n, 3) array: {exc}") from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"{name} must have shape (n, 3), got {arr.shape}")
    if not allow_empty and arr.shape[0] == 0:
        raise InputError(f"{name} is empty: the mesh has no vertices")
    if not np.isfinite(arr).all():
        bad = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
        raise InputError(f"{name} has non-finite coordinates (first at vertex {bad})")
    return arr


def as_faces(F, n_vertices: int | None = None, *, name: str = "F",
             allow_empty: bool = True) -> np.ndarray:
    """Return ``F`` as a C-contiguous ``(m, 3)`` int64 array of vertex indices.

    Parameters
    ----------
    F : array_like, (m, 3)
        Triangle corner indices.
    n_vertices : int, optional
        When given, every index must lie in ``[0, n_vertices)``.
    name : str, optional
        Argument name used in error messages.
    allow_empty : bool, optional
        Accept ``m == 0``.

    Returns
    -------
    numpy.ndarray, (m, 3) int64

    Raises
    ------
    InputError
        On a wrong shape, non-integer values, or out-of-range indices.
    """
    raw = np.asarray(F)
    if raw.size == 0:
        raw = raw.reshape(0, 3) if raw.ndim < 2 else raw
    if raw.dtype.kind == "f":
        if not np.all(np.isfinite(raw)) or np.any(raw != np.round(raw)):
            raise InputError(f"{name} must hold integer vertex indices")
    elif raw.dtype.kind not in "iub":
        raise InputError(f"{name} must be an integer (m, 3) array, got dtype {raw.dtype}")
    arr = np.ascontiguousarray(raw, dtype=np.int64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"{name} must have shape (m, 3), got {arr.shape}")
    if not allow_empty and arr.shape[0] == 0:
        raise InputError(f"{name} is empty: the mesh has no faces")
    if n_vertices is not None and arr.size:
        lo, hi = int(arr.min()), int(arr.max())
        if lo < 0 or hi >= n_vertices:
            bad = int(np.flatnonzero(((arr < 0) | (arr >= n_vertices)).any(axis=1))[0])
            raise InputError(
                f"{name} references vertex indices outside [0, {n_vertices}) "
                f"(first at face {bad}: {arr[bad].tolist()})")
    return arr


def as_mesh_arrays(V, F, *, allow_empty: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Validate a pair ``(V, F)``; see :func:`as_vertices` and :func:`as_faces`.

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    """
    V = as_vertices(V, allow_empty=allow_empty)
    F = as_faces(F, V.shape[0], allow_empty=allow_empty)
    return V, F


def mesh_digest(V: np.ndarray, F: np.ndarray) -> str:
    """Return a fingerprint of the exact arrays ``(V, F)`` (hex BLAKE2b, 128 bits).

    Two meshes have the same digest when their float64 coordinates and int64
    faces are bit-for-bit equal, in the same order. A validity report keeps
    the digest of the arrays it judged, so a writer can tell whether the
    report describes exactly what it is about to store.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64

    Returns
    -------
    str
    """
    import hashlib

    h = hashlib.blake2b(digest_size=16)
    for a, dtype in ((V, np.float64), (F, np.int64)):
        a = np.ascontiguousarray(a, dtype=dtype)
        h.update(str(a.shape).encode())
        h.update(a.reshape(-1).view(np.uint8))
    return h.hexdigest()
