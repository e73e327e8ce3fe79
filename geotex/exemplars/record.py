"""The :class:`Exemplar` record: a planar patch of separate closed texture elements."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from geotex.errors import InputError

from geotex.mesh.arrays import as_faces, as_vertices
from geotex.mesh.record import Mesh
from geotex.mesh.geometry import group_boxes
from geotex.mesh.topology import compacted, face_components

__all__ = ["Exemplar"]


@dataclass(frozen=True, eq=False)
class Exemplar:
    """A planar patch of geometric texture made of separate closed elements.

    Units: one Wang tile is 1 x 1.  Elements stand on the plane ``z = 0`` and
    sink to ``z = -depth`` so that a union with a base below ``z = 0`` fuses
    them; every element lies over ``[0, lx] x [0, ly]``.

    Parameters
    ----------
    vertices : array_like, (n, 3) float64
    faces : array_like, (m, 3) int64
        Outward oriented; every connected component is one closed element.
    size : tuple of float
        Patch extent ``(lx, ly)``.
    height : float
        The largest ``z`` of any element.
    depth : float
        Elements reach down to ``z = -depth``.
    name : str
        Kind name (``"studs"``, ...) or the stem of the file it was read from.
    params : dict
        JSON-serialisable recipe, seed and size included: for a procedural
        exemplar ``geotex.exemplars.exemplar(name, **params)`` rebuilds it
        byte-identically.  Empty for an exemplar read from a plain mesh file.
    period : tuple of float, optional
        ``(px, py)``: the lattice of cell multiples ``(m px, n py)`` that
        holds the translations mapping the pattern onto itself (up to the
        jitter): all of them for chain mail (one ring spacing along a row,
        two row spacings across, since the rows alternate their tilt), those
        with ``m + n`` even for rows offset by half a step (scales).  Mesh
        quilting places copies on this lattice and its matching energy
        picks the right ones.  None when unknown.

    Raises
    ------
    InputError
        If the arrays are malformed (see :func:`geotex.mesh.as_vertices`).
    """

    vertices: np.ndarray
    faces: np.ndarray
    size: tuple
    height: float
    depth: float
    name: str = ""
    params: dict = field(default_factory=dict)
    period: tuple | None = None

    def __post_init__(self):
        V = as_vertices(self.vertices, name="vertices")
        F = as_faces(self.faces, V.shape[0], name="faces")
        object.__setattr__(self, "vertices", V)
        object.__setattr__(self, "faces", F)
        object.__setattr__(self, "size", (float(self.size[0]), float(self.size[1])))
        object.__setattr__(self, "height", float(self.height))
        object.__setattr__(self, "depth", float(self.depth))
        if self.period is not None:
            try:
                px, py = (float(c) for c in self.period)
            except (TypeError, ValueError):
                raise InputError(f"period must be two positive numbers (px, py), "
                                 f"got {self.period!r}") from None
            if not (math.isfinite(px) and math.isfinite(py) and px > 0 and py > 0):
                raise InputError(f"period must be two positive numbers (px, py), "
                                 f"got {self.period!r}")
            object.__setattr__(self, "period", (px, py))

    def elements(self) -> np.ndarray:
        """Return the element id of every face.

        Returns
        -------
        numpy.ndarray, (m,) int64
            Connected components (faces sharing a vertex), numbered in the
            order of their first face.
        """
        return face_components(self.faces, self.vertices.shape[0])[1]

    @property
    def n_elements(self) -> int:
        """Number of elements (connected components)."""
        return int(face_components(self.faces, self.vertices.shape[0])[0])

    def mesh(self) -> Mesh:
        """Return the elements as a :class:`~geotex.mesh.Mesh` (recipe in ``metadata``)."""
        return Mesh(self.vertices, self.faces, name=self.name,
                    metadata={"exemplar": self.name, "params": dict(self.params)})

    def cropped(self, extent) -> "Exemplar":
        """The elements lying wholly in ``[0, ex] x [0, ey]``, as a smaller exemplar.

        Parameters
        ----------
        extent : tuple of 2 float
            ``(ex, ey)``, the new ``size``.

        Returns
        -------
        Exemplar
            Same name, height, depth and period; ``params`` gain
            ``"cropped": [ex, ey]`` (the procedural recipe alone no longer
            rebuilds it).

        Raises
        ------
        InputError
            A non-positive extent, or no element lies wholly inside it.

        Examples
        --------
        >>> from geotex.exemplars import exemplar
        >>> small = exemplar("studs", size=(4, 4)).cropped((1.3, 1.3))
        >>> small.size, small.n_elements
        ((1.3, 1.3), 4)
        """
        try:
            ex, ey = (float(e) for e in extent)
        except (TypeError, ValueError):
            raise InputError(f"extent must be two numbers (ex, ey), got {extent!r}") from None
        if not (ex > 0 and ey > 0 and math.isfinite(ex) and math.isfinite(ey)):
            raise InputError(f"extent must be positive, got {extent!r}")
        V, F = self.vertices, self.faces
        n, labels = face_components(F, V.shape[0])
        vlab = np.full(V.shape[0], -1, dtype=np.int64)
        vlab[F.ravel()] = np.repeat(labels, 3)
        lo, hi = group_boxes(V, vlab, n)
        inside = ((lo[:, :2] >= 0.0) & (hi[:, :2] <= [ex, ey])).all(axis=1)
        if not inside.any():
            raise InputError(f"no element of the exemplar lies wholly in [0, {ex:g}] x "
                             f"[0, {ey:g}]")
        Vk, Fk = compacted(V, F[inside[labels]])
        return Exemplar(Vk, Fk, (ex, ey), self.height, self.depth, self.name,
                        {**self.params, "cropped": [ex, ey]}, self.period)

    def __repr__(self) -> str:
        return (f"Exemplar({self.name!r}, size={self.size}, {self.n_elements} elements, "
                f"{self.faces.shape[0]} faces, height={self.height:.4g}, "
                f"depth={self.depth:.4g})")
