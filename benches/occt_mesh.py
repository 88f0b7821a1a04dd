#!/usr/bin/env python3
"""Open CASCADE BRepMesh baseline for `benches/step_compare.rs`.

Usage: occt_mesh.py FILE TOL_ABS [TOL_ABS ...] [--units file|mm|auto] [--match-diag D] [--rel]
                   [--by-kind]

Reads FILE with STEPControl_Reader (TransferRoots, OneShape), then for every absolute tolerance
meshes the whole shape with `BRepMesh_IncrementalMesh(shape, tol, False, 0.5, False)` (linear
deflection `tol`, angular deflection 0.5 rad, not relative, not parallel) and prints one JSON
object per line on stdout:

    {"tool": "occt", "file": ..., "tol": ..., "read_ms": ..., "mesh_ms": ..., "triangles": ...,
     "faces": ..., "faces_meshed": ..., "max_error": ..., "error_ratio": ..., "unprojected": ...,
     "samples": ..., "sampled": ..., "sample_ms": ..., "bbox_diag": ..., "bbox_diag_mm": ...,
     "bbox_diag_shape": ..., "units": ..., "unit_scale": ..., "file_unit": ..., "mm_per_unit": ...}

Units. OCCT reads lengths in millimetres; another reader may keep the file's own unit. TOL_ABS
and every length printed (`tol`, `max_error`, `bbox_diag`) are in the *output unit*:
`--units file` (the default) the file's declared length unit, `--units mm` millimetres, and
`--units auto --match-diag D` whichever of the two gives a bounding-box diagonal closer to D
(the other reader's diagonal; the unit factors, 10 to 1000, dwarf any difference in boxes).
The shape stays in millimetres: tolerances are multiplied by `unit_scale` (mm per output unit)
before meshing and lengths divided by it, which is exact since BRepMesh's angular deflection does
not depend on scale. `bbox_diag_mm` is the diagonal in millimetres.

`bbox_diag` is the tight box of the faces (`BRepBndLib.AddOptimal_s` per face, no triangulation,
no tolerance enlargement), comparable with a box computed from the faces' geometry.
`bbox_diag_shape` is `BRepBndLib.Add_s` on the whole shape (looser: control points, tolerances,
and any non-face geometry the file carries).

Measured error. For every triangle of every face the centroid and the three edge midpoints are
projected onto the face's surface (`BRep_Tool.Surface_s(face)`, which carries the face's
location) with `GeomAPI_ProjectPointOnSurf`; `max_error` is the largest `LowerDistance`. Samples
whose projection fails are counted in `unprojected`, not ignored. If a model has more than
`MAX_SAMPLES` samples, every k-th triangle is sampled and `sampled` is the fraction of triangles
used (1.0 otherwise). This measures the distance from the mesh to the untrimmed surface, a lower
bound of the two-sided distance to the trimmed face, and exact for the interior of each triangle
only at the sampled points.

With `--by-kind` (for `benches/occt_faces.rs`), after each tolerance's row one line per surface
kind follows, counting every face once however often the assembly places it (faces are told
apart by their `TShape`, located at the identity and oriented forward: BRepMesh stores one
triangulation per `TShape`, so instanced faces are meshed once, as ours are):

    {"tool": "occt-kind", "file": ..., "tol": ..., "kind": ..., "faces": ..., "faces_meshed": ...,
     "triangles": ...}

`kind` is the `GeomAdaptor_Surface` type of `BRep_Tool.Surface_s` in our names: plane, cylinder,
cone, sphere, torus, bspline (B-spline and Bézier, rational or not), swept (revolution and
extrusion), offset, other. The measuring pass (and its time) is skipped with `--by-kind`.

With `--rel` the tolerances are fractions of OCCT's own bounding-box diagonal instead (the
"tol" field of the output is then the absolute tolerance used, "tol_rel" the fraction).

The triangulation is removed with `BRepTools.Clean_s` before every tolerance, so each run meshes
from scratch. Failures (read or mesh) are reported as a JSON line with an "error" field.
"""

import argparse
import json
import math
import sys
import time

from OCP.BRep import BRep_Tool
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepTools import BRepTools
from OCP.Bnd import Bnd_Box
from OCP.Extrema import Extrema_ExtAlgo_Tree, Extrema_ExtFlag_MIN, Extrema_GenLocateExtPS
from OCP.GeomAbs import (
    GeomAbs_BezierSurface,
    GeomAbs_BSplineSurface,
    GeomAbs_Cone,
    GeomAbs_Cylinder,
    GeomAbs_OffsetSurface,
    GeomAbs_Plane,
    GeomAbs_Sphere,
    GeomAbs_SurfaceOfExtrusion,
    GeomAbs_SurfaceOfRevolution,
    GeomAbs_Torus,
)
from OCP.GeomAdaptor import GeomAdaptor_Surface
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Pnt
from OCP.IFSelect import IFSelect_RetDone
from OCP.OCP.collections import Sequence_TCollection_AsciiString
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_FACE, TopAbs_FORWARD
from OCP.TopExp import TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS

ANGULAR_DEFLECTION = 0.5
"""Angular deflection of BRepMesh, radians."""

MAX_SAMPLES = 200_000
"""Above this many samples (4 per triangle), triangles are subsampled evenly."""

PROJECTION_TOLERANCE = 1e-9
"""Parametric tolerance of the point projections."""

INFINITE = 1e50
"""Parameter bounds beyond this are treated as infinite (OCCT uses 2e100)."""

MM_PER_UNIT = {
    "millimetre": 1.0,
    "millimeter": 1.0,
    "mm": 1.0,
    "centimetre": 10.0,
    "centimeter": 10.0,
    "cm": 10.0,
    "metre": 1000.0,
    "meter": 1000.0,
    "m": 1000.0,
    "micrometre": 1e-3,
    "micrometer": 1e-3,
    "inch": 25.4,
    "in": 25.4,
    "foot": 304.8,
    "ft": 304.8,
}
"""Millimetres per file length unit, by the lower-cased names STEPControl_Reader.FileUnits gives."""


def emit(obj):
    print(json.dumps(obj), flush=True)


def file_length_unit(reader):
    """(name, mm per unit) of the file's first declared length unit; (None, None) if unknown."""
    lengths = Sequence_TCollection_AsciiString()
    angles, solid_angles = Sequence_TCollection_AsciiString(), Sequence_TCollection_AsciiString()
    reader.FileUnits(lengths, angles, solid_angles)
    names = [lengths.Value(i).ToCString() for i in range(1, lengths.Length() + 1)]
    if not names:
        return None, None
    # Several representations may declare different units; the first one wins (a mixed-unit
    # file is reported with its first unit and read in millimetres by the caller's check).
    scales = {MM_PER_UNIT.get(n.lower()) for n in names}
    name = names[0]
    if len(scales) != 1:
        return name, None
    return name, MM_PER_UNIT.get(name.lower())


def bbox_diagonal(shape):
    """Diagonal of OCCT's default (loose) box of the whole shape."""
    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box, False)
    if box.IsVoid():
        return 0.0
    return math.sqrt(box.SquareExtent())


def faces_bbox_diagonal(faces):
    """Diagonal of the tight box of the faces' geometry."""
    box = Bnd_Box()
    for face in faces:
        BRepBndLib.AddOptimal_s(face, box, False, False)
    if box.IsVoid():
        return 0.0
    return math.sqrt(box.SquareExtent())


def faces_of(shape):
    out = []
    explorer = TopExp_Explorer(shape, TopAbs_FACE)
    while explorer.More():
        out.append(TopoDS.Face(explorer.Current()))
        explorer.Next()
    return out


class SurfaceDistance:
    """Distance from points to one face's (untrimmed) surface.

    Planes, cylinders and spheres are measured in closed form (the same value a projection
    gives, without its cost). Other surfaces are first searched locally from a parameter hint
    (`Extrema_GenLocateExtPS`, a few microseconds), which gives a local minimum, never less than
    the true distance; when that is not below `floor` (it could raise the model's maximum) or
    fails, the global `GeomAPI_ProjectPointOnSurf` is asked as well and the smaller distance
    kept. The maximum over a model is therefore the same as with global projections only.
    """

    def __init__(self, face):
        self.face = face
        self.surface = BRep_Tool.Surface_s(face)
        adaptor = GeomAdaptor_Surface(self.surface)
        kind = adaptor.GetType()
        self.kind = None
        self.local = None
        self.projector = None
        self.global_calls = 0
        if kind == GeomAbs_Plane:
            pln = adaptor.Plane()
            o, n = pln.Location(), pln.Axis().Direction()
            self.kind = "plane"
            self.data = (o.X(), o.Y(), o.Z(), n.X(), n.Y(), n.Z())
        elif kind == GeomAbs_Cylinder:
            cyl = adaptor.Cylinder()
            o, d = cyl.Location(), cyl.Axis().Direction()
            self.kind = "cylinder"
            self.data = (o.X(), o.Y(), o.Z(), d.X(), d.Y(), d.Z(), cyl.Radius())
        elif kind == GeomAbs_Sphere:
            sph = adaptor.Sphere()
            o = sph.Location()
            self.kind = "sphere"
            self.data = (o.X(), o.Y(), o.Z(), sph.Radius())
        else:
            self.adaptor = adaptor
            tol = PROJECTION_TOLERANCE
            self.local = Extrema_GenLocateExtPS(adaptor, tol, tol)

    def global_distance(self, point):
        if self.projector is None:
            # The surface's own domain, with infinite directions (extrusions, offsets of
            # unbounded surfaces) clamped to the face's UV box widened by its size each side.
            u0, u1, v0, v1 = self.surface.Bounds()
            fu0, fu1, fv0, fv1 = BRepTools.UVBounds_s(self.face)
            du, dv = fu1 - fu0, fv1 - fv0
            if u0 < -INFINITE or u1 > INFINITE:
                u0, u1 = max(u0, fu0 - du), min(u1, fu1 + du)
            if v0 < -INFINITE or v1 > INFINITE:
                v0, v1 = max(v0, fv0 - dv), min(v1, fv1 + dv)
            self.projector = GeomAPI_ProjectPointOnSurf()
            self.projector.Init(self.surface, u0, u1, v0, v1, PROJECTION_TOLERANCE)
            self.projector.SetExtremaAlgo(Extrema_ExtAlgo_Tree)
            self.projector.SetExtremaFlag(Extrema_ExtFlag_MIN)
        self.global_calls += 1
        self.projector.Perform(point)
        if not self.projector.IsDone() or self.projector.NbPoints() == 0:
            return None
        return self.projector.LowerDistance()

    def __call__(self, x, y, z, uv, floor):
        """Distance of (x, y, z), or None if no projection was found.

        `uv` is a parameter hint or None; `floor` the largest distance seen so far.
        """
        if self.kind == "plane":
            ox, oy, oz, nx, ny, nz = self.data
            return abs((x - ox) * nx + (y - oy) * ny + (z - oz) * nz)
        if self.kind == "cylinder":
            ox, oy, oz, dx, dy, dz, r = self.data
            vx, vy, vz = x - ox, y - oy, z - oz
            t = vx * dx + vy * dy + vz * dz
            radial = math.sqrt(max(vx * vx + vy * vy + vz * vz - t * t, 0.0))
            return abs(radial - r)
        if self.kind == "sphere":
            ox, oy, oz, r = self.data
            return abs(math.sqrt((x - ox) ** 2 + (y - oy) ** 2 + (z - oz) ** 2) - r)
        point = gp_Pnt(x, y, z)
        local = None
        if uv is not None:
            self.local.Perform(point, uv[0], uv[1], True)
            if self.local.IsDone():
                local = math.sqrt(self.local.SquareDistance())
                if local <= floor:
                    return local
        found = self.global_distance(point)
        if found is None:
            return local
        return found if local is None else min(local, found)


def face_triangles(face):
    """(world-space nodes, UV nodes or None, 0-based triangles), or None if not triangulated."""
    loc = TopLoc_Location()
    tri = BRep_Tool.Triangulation_s(face, loc)
    if tri is None or tri.NbTriangles() == 0:
        return None
    trsf = loc.Transformation()
    identity = loc.IsIdentity()
    nodes = []
    for i in range(1, tri.NbNodes() + 1):
        p = tri.Node(i)
        if not identity:
            p = p.Transformed(trsf)
        nodes.append((p.X(), p.Y(), p.Z()))
    uvs = None
    if tri.HasUVNodes():
        uvs = []
        for i in range(1, tri.NbNodes() + 1):
            q = tri.UVNode(i)
            uvs.append((q.X(), q.Y()))
    triangles = []
    for i in range(1, tri.NbTriangles() + 1):
        a, b, c = tri.Triangle(i).Get()
        triangles.append((a - 1, b - 1, c - 1))
    return nodes, uvs, triangles


SURFACE_KINDS = {
    GeomAbs_Plane: "plane",
    GeomAbs_Cylinder: "cylinder",
    GeomAbs_Cone: "cone",
    GeomAbs_Sphere: "sphere",
    GeomAbs_Torus: "torus",
    GeomAbs_BezierSurface: "bspline",
    GeomAbs_BSplineSurface: "bspline",
    GeomAbs_SurfaceOfRevolution: "swept",
    GeomAbs_SurfaceOfExtrusion: "swept",
    GeomAbs_OffsetSurface: "offset",
}
"""`GeomAbs` surface types in the names `benches/occt_faces.rs` gives ours."""


def unique_faces(faces):
    """Each `TShape` once (the first occurrence), with its surface kind: [(face, kind)]."""
    seen = {}  # hash -> the unlocated faces with it (Python's == on shapes is identity)
    out = []
    for face in faces:
        key = face.Located(TopLoc_Location()).Oriented(TopAbs_FORWARD)
        same = seen.setdefault(hash(key), [])
        if any(key.IsSame(other) for other in same):
            continue
        same.append(key)
        kind = GeomAdaptor_Surface(BRep_Tool.Surface_s(face)).GetType()
        out.append((face, SURFACE_KINDS.get(kind, "other")))
    return out


def kind_rows(base, tol, unique):
    """One `occt-kind` row per surface kind of the faces in `unique` (see the module doc)."""
    by_kind = {}
    for face, kind in unique:
        ft = face_triangles(face)
        n = 0 if ft is None else len(ft[2])
        row = by_kind.setdefault(kind, [0, 0, 0])
        row[0] += 1
        row[1] += n > 0
        row[2] += n
    for kind, (faces, meshed, triangles) in sorted(by_kind.items()):
        emit({**base, "tool": "occt-kind", "tol": tol, "kind": kind, "faces": faces,
              "faces_meshed": meshed, "triangles": triangles})


def mid(*points):
    n = len(points)
    return tuple(sum(c) / n for c in zip(*points))


def measure(faces, meshed):
    """Max distance over the samples, with counts; `meshed` is [(face, nodes, uvs, tris)]."""
    total = sum(len(t) for _, _, _, t in meshed)
    stride = max(1, math.ceil(4 * total / MAX_SAMPLES))
    max_error, max_face, samples, unprojected, used, global_calls = 0.0, None, 0, 0, 0, 0
    counter = 0
    for face_index, nodes, uvs, triangles in meshed:
        distance = None
        for a, b, c in triangles:
            counter += 1
            if (counter - 1) % stride:
                continue
            if distance is None:
                distance = SurfaceDistance(faces[face_index])
            used += 1
            pa, pb, pc = nodes[a], nodes[b], nodes[c]
            points = (mid(pa, pb, pc), mid(pa, pb), mid(pb, pc), mid(pc, pa))
            if uvs is None:
                hints = (None,) * 4
            else:
                qa, qb, qc = uvs[a], uvs[b], uvs[c]
                hints = (mid(qa, qb, qc), mid(qa, qb), mid(qb, qc), mid(qc, qa))
            for (x, y, z), uv in zip(points, hints):
                samples += 1
                d = distance(x, y, z, uv, max_error)
                if d is None:
                    unprojected += 1
                elif d > max_error:
                    max_error, max_face = d, face_index
        if distance is not None:
            global_calls += distance.global_calls
    sampled = used / total if total else 1.0
    return max_error, max_face, samples, unprojected, sampled, global_calls


def run(path, tolerances, units, match_diag, relative, by_kind=False):
    base = {"tool": "occt", "file": path}
    t0 = time.perf_counter()
    reader = STEPControl_Reader()
    status = reader.ReadFile(path)
    if status != IFSelect_RetDone:
        emit({**base, "error": f"STEPControl_Reader.ReadFile returned {status}"})
        return 1
    unit_name, mm_per_unit = file_length_unit(reader)
    reader.TransferRoots()
    shape = reader.OneShape()
    read_ms = (time.perf_counter() - t0) * 1e3
    if shape is None or shape.IsNull():
        emit({**base, "read_ms": read_ms, "error": "no shape transferred"})
        return 1
    faces = faces_of(shape)
    diag_mm = faces_bbox_diagonal(faces)
    # Output unit: millimetres (scale 1) or the file's unit (scale = mm per file unit).
    file_scale = mm_per_unit if mm_per_unit is not None else 1.0
    if units == "mm":
        scale = 1.0
    elif units == "file":
        scale = file_scale
    else:
        def misfit(k):
            return abs(math.log(max(diag_mm / k, 1e-300) / match_diag))

        scale = min((1.0, file_scale), key=misfit)
    diag = diag_mm / scale
    common = {
        **base,
        "read_ms": read_ms,
        "bbox_diag": diag,
        "bbox_diag_mm": diag_mm,
        "bbox_diag_shape": bbox_diagonal(shape) / scale,
        "units": "mm" if scale == 1.0 else "file",
        "unit_scale": scale,
        "file_unit": unit_name,
        "mm_per_unit": mm_per_unit,
        "faces": len(faces),
    }
    unique = unique_faces(faces) if by_kind else None
    for tol in tolerances:
        row = {**common, "tol": tol}
        if relative:
            row["tol_rel"] = tol
            tol = row["tol"] = tol * diag
        try:
            BRepTools.Clean_s(shape)
            t = time.perf_counter()
            mesher = BRepMesh_IncrementalMesh(
                shape, tol * scale, False, ANGULAR_DEFLECTION, False
            )
            mesh_ms = (time.perf_counter() - t) * 1e3
            row["mesh_ms"] = mesh_ms
            row["mesh_done"] = bool(mesher.IsDone())
            meshed = []
            for i, face in enumerate(faces):
                ft = face_triangles(face)
                if ft is not None:
                    meshed.append((i, *ft))
            row["triangles"] = sum(len(t) for _, _, _, t in meshed)
            row["faces_meshed"] = len(meshed)
            if unique is not None:
                row["unique_faces"] = len(unique)
                emit(row)
                kind_rows(base, tol, unique)
                continue
            t = time.perf_counter()
            measured = measure(faces, meshed)
            max_error, max_face, samples, unprojected, sampled, global_calls = measured
            max_error /= scale
            row.update(
                max_error=max_error,
                error_ratio=max_error / tol if tol > 0 else None,
                max_error_face=max_face,
                samples=samples,
                unprojected=unprojected,
                sampled=sampled,
                global_projections=global_calls,
                sample_ms=(time.perf_counter() - t) * 1e3,
            )
        except Exception as e:  # noqa: BLE001 - report any OCCT failure as a row, keep going
            row["error"] = f"{type(e).__name__}: {e}"
        emit(row)
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("file")
    parser.add_argument("tolerances", nargs="+", type=float, metavar="TOL_ABS")
    parser.add_argument(
        "--units",
        choices=("file", "mm", "auto"),
        default="file",
        help="length unit of TOL_ABS and of the output: the file's own (default), mm, or the "
        "one whose diagonal is closer to --match-diag",
    )
    parser.add_argument(
        "--match-diag",
        type=float,
        metavar="D",
        help="the other reader's bounding-box diagonal, for --units auto",
    )
    parser.add_argument(
        "--rel",
        action="store_true",
        help="the tolerances are fractions of OCCT's bounding-box diagonal",
    )
    parser.add_argument(
        "--by-kind",
        action="store_true",
        help="after each row, triangles per surface kind over the unique faces (no measuring)",
    )
    args = parser.parse_args()
    bad = [t for t in args.tolerances if not (t > 0 and math.isfinite(t))]
    if bad:
        parser.error(f"tolerances must be positive and finite: {bad}")
    if args.units == "auto" and not (args.match_diag and args.match_diag > 0):
        parser.error("--units auto needs a positive --match-diag")
    return run(args.file, args.tolerances, args.units, args.match_diag, args.rel, args.by_kind)


if __name__ == "__main__":
    sys.exit(main())
