"""Mesh files (STL, OBJ, DAE, ...) as the animation draws them: read by trimesh (an optional
dependency: ``pip install trimesh pycollada``), merged into one triangle list and coarsened
to at most FACES triangles by vertex clustering, so that a robot of ten detailed links stays
a page of a few hundred kilobytes and a GIF drawn in seconds."""

import functools
import os
import warnings

import numpy as np

from ..errors import KinetworkWarning

#: triangles per mesh at most, as drawn
FACES = 500
#: cells per side of the clustering grids tried, finest first
GRIDS = (96, 72, 56, 44, 34, 26, 20, 15, 11, 8, 6, 4)


def mesh(path, faces=FACES):
    """(vertices (n, 3), triangles (m, 3)) of the file ``path``, coarsened to at most
    ``faces`` triangles; None (with a warning) when it cannot be read."""
    try:
        stamp = os.stat(path).st_mtime_ns
    except OSError:
        warnings.warn(KinetworkWarning(f"animation: mesh file {path!r:.200} not found: drawn "
                                       f"without it"), stacklevel=3)
        return None
    return _read(os.path.abspath(path), stamp, faces)


@functools.lru_cache(maxsize=128)
def _read(path, stamp, faces):
    try:
        import trimesh
    except ImportError:
        warnings.warn(KinetworkWarning("animation: meshes need trimesh (pip install trimesh "
                                       "pycollada): the robot is drawn without them"),
                      stacklevel=4)
        return None
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
        vertices = np.asarray(loaded.vertices, dtype=float)
        triangles = np.asarray(loaded.faces, dtype=np.int64).reshape(-1, 3)
    except Exception as exc:         # a loader's own error, whatever it is: drawn without
        warnings.warn(KinetworkWarning(f"animation: cannot read mesh {path!r:.200}: {exc}"),
                      stacklevel=4)
        return None
    if not len(triangles) or not np.all(np.isfinite(vertices)):
        return None
    return coarsened(vertices, triangles, faces)


def coarsened(vertices, triangles, faces=FACES):
    """The mesh with at most ``faces`` triangles: vertices merged per cell of the finest grid
    over its bounding box that leaves few enough, each cluster at its vertices' mean;
    triangles that collapse or repeat dropped."""
    if len(triangles) <= faces:
        return vertices, triangles
    lo = vertices.min(axis=0)
    extent = float(np.ptp(vertices, axis=0).max()) or 1.0
    for cells in GRIDS:
        keys = np.floor((vertices - lo) / (extent / cells)).astype(np.int64)
        _, cluster = np.unique(keys, axis=0, return_inverse=True)
        cluster = cluster.ravel()
        count = np.bincount(cluster)
        merged = np.zeros((len(count), 3))
        np.add.at(merged, cluster, vertices)
        merged /= count[:, None]
        tri = cluster[triangles]
        keep = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])
        tri = tri[keep]
        _, first = np.unique(np.sort(tri, axis=1), axis=0, return_index=True)
        tri = tri[np.sort(first)]
        if len(tri) <= faces:
            return _compact(merged, tri)
    return _compact(merged, tri[:faces])


def _compact(vertices, triangles):
    """Only the vertices the triangles use, renumbered."""
    used, inverse = np.unique(triangles, return_inverse=True)
    return vertices[used], inverse.reshape(triangles.shape)
