"""The largest distance from a set of points to a triangle mesh, exact, without visiting every
point's neighbourhood: the mesh judge's measurement (tools/mesh_vs_meshopt.py), written on
numpy and scipy's k-d tree only (no code of patchwork's, and none of trimesh's: `--self-test`
checks it against trimesh's closest points).

`farthest(points, triangles)`:
1. every point's distance to the triangles of its K nearest centroids (exact point-triangle
   distances): an upper bound `upper[p]` of its distance to the mesh;
2. points taken in decreasing `upper` order, a batch at a time, each measured exactly: a
   triangle nearer than `upper[p]` has its centroid within `upper[p] + r` of p (r: that
   triangle's circumscribing radius about its centroid), so a ball query per radius class
   (classes of radii within a factor 2, each its own tree) lists every candidate;
3. it stops when the next point's `upper` is no more than the largest exact distance found:
   no remaining point can be farther.
The answer is the exact maximum (up to float64 rounding); only the points that could be it are
measured in full.
"""

import numpy as np
from scipy.spatial import cKDTree

# Nearest centroids whose triangles give each point's first upper bound.
K = 4
# Points measured exactly per step of the descending walk.
BATCH = 512


def point_triangle_distance(p, a, b, c):
    """Row-wise distance from p[i] to the triangle a[i] b[i] c[i] (arrays of shape (n, 3)):
    the plane distance where the projection falls inside, else the nearest of the three sides
    (a degenerate triangle is its sides)."""
    def segment(p, s, t):
        d = t - s
        dd = np.einsum("ij,ij->i", d, d)
        u = np.einsum("ij,ij->i", p - s, d)
        u = np.divide(u, dd, out=np.zeros_like(u), where=dd > 0)
        u = np.clip(u, 0.0, 1.0)
        q = s + u[:, None] * d
        return np.linalg.norm(p - q, axis=1)

    best = np.minimum(np.minimum(segment(p, a, b), segment(p, b, c)), segment(p, c, a))
    n = np.cross(b - a, c - a)
    nn = np.einsum("ij,ij->i", n, n)
    ok = nn > 0
    inside = ok.copy()
    for s, t in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(t - s, p - s), n) >= 0
    plane = np.abs(np.einsum("ij,ij->i", p - a, n)) / np.sqrt(np.where(ok, nn, 1.0))
    return np.where(inside, np.minimum(plane, best), best)


class Mesh:
    """The triangles of a mesh (shape (m, 3, 3)) with the search structures `farthest` uses."""

    def __init__(self, triangles):
        tris = np.asarray(triangles, dtype=np.float64)
        if tris.ndim != 3 or tris.shape[1:] != (3, 3) or len(tris) == 0:
            raise ValueError("expected a non-empty (m, 3, 3) array of triangles")
        self.tris = tris
        centroid = tris.mean(axis=1)
        radius = np.linalg.norm(tris - centroid[:, None, :], axis=2).max(axis=1)
        self.tree = cKDTree(centroid)
        # Radius classes: [r_min * 2^k, r_min * 2^(k+1)); a zero radius (a point triangle)
        # joins the smallest class.
        positive = radius[radius > 0]
        r0 = positive.min() if len(positive) else 1.0
        cls = np.floor(np.log2(np.maximum(radius, r0) / r0)).astype(int)
        self.classes = []
        for k in np.unique(cls):
            ids = np.nonzero(cls == k)[0]
            self.classes.append((ids, cKDTree(centroid[ids]), float(radius[ids].max())))

    def distances(self, points, ids):
        """Distance from each point to the triangles ids[i] (flat pairs)."""
        t = self.tris[ids]
        return point_triangle_distance(points, t[:, 0], t[:, 1], t[:, 2])

    def exact(self, points, upper):
        """Each point's exact distance to the mesh, given an upper bound of it."""
        best = upper.copy()
        for ids, tree, r in self.classes:
            lists = tree.query_ball_point(points, upper + r * (1 + 1e-12) + 1e-12,
                                          return_sorted=False, workers=-1)
            counts = np.fromiter((len(x) for x in lists), dtype=np.intp, count=len(lists))
            if counts.sum() == 0:
                continue
            owner = np.repeat(np.arange(len(points)), counts)
            tri = ids[np.concatenate([np.asarray(x, dtype=np.intp) for x in lists])]
            d = self.distances(points[owner], tri)
            np.minimum.at(best, owner, d)
        return best

    def upper(self, points):
        """Each point's distance to the triangles of its K nearest centroids."""
        k = min(K, len(self.tris))
        _, near = self.tree.query(points, k=k, workers=-1)
        near = near.reshape(len(points), k)
        owner = np.repeat(np.arange(len(points)), k)
        d = self.distances(points[owner], near.reshape(-1))
        return d.reshape(len(points), k).min(axis=1)

    def farthest(self, points):
        """The largest over `points` of the exact distance to the mesh, and how many points
        were measured in full."""
        points = np.asarray(points, dtype=np.float64)
        if len(points) == 0:
            return 0.0, 0
        upper = self.upper(points)
        order = np.argsort(-upper, kind="stable")
        worst, measured = 0.0, 0
        for start in range(0, len(order), BATCH):
            batch = order[start:start + BATCH]
            if upper[batch[0]] <= worst:
                break
            worst = max(worst, float(self.exact(points[batch], upper[batch]).max()))
            measured += len(batch)
        return worst, measured


def farthest(points, triangles):
    """`Mesh(triangles).farthest(points)[0]`."""
    return Mesh(triangles).farthest(points)[0]
