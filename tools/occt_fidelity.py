#!/usr/bin/env python3
"""Independent fidelity judge: patchwork's export against Open CASCADE.

For every STEP or IGES file of the corpus (default: models/*.{stp,step,igs,iges},
models/corpus/*.{stp,step,igs,iges}[.gz] and models/generated/*.step[.gz], the generator's failures
kept reduced) and every relative tolerance `rel`, or for N models of the seeded generator
(tools/cad_generator.py; `--generate N --gen-seed S [--gen-start K] [--reduce-to DIR]`):

  T = rel x diagonal of OCCT's world bounding box (millimetres).

Our side: `patchwork export FILE -o OUT.glb --tolerance T --unit model --up model`; the GLB is read with its
node hierarchy (world matrix = product along the parents); `asset.extras` or node
`extras` `{"unit": "mm"|"m", "up": "z"|"y"}` are honoured (default mm, z-up), see
`read_glb`.

OCCT side: STEPCAFControl_Reader into an XCAF document (lengths in mm), every free
shape walked through its components with XCAFDoc_ShapeTool.GetLocation_s to the
leaves; a leaf part contributes one placed instance per solid, per shell outside a
solid and one for faces outside any shell (compounds are expanded). Each part is
meshed once with BRepMesh_IncrementalMesh(shape, T/10, False, 0.5, True) and its
triangles are placed by the instance's world location. A generated model's parts are judged
as OCCT built them (cad_generator.build_step writes them beside the STEP in OCCT's own
format), not as OCCT reads back the STEP it wrote: the round trip can change a face (seed 7
model 6: a sphere's face read back with its hole covered twice); where the two differ the
report says so ("judged as built"). A model that fails against the parts is judged again
against OCCT's reading of the STEP where that reading differs from them and is a valid shape
(BRepCheck): OCCT's writer does not always write what it built (seed 12 model 48: 7 faces
left out); it passes there only ("judged as read back").

Checks (a file fails if any does):
  (c) assembly: the number of placed instances is the same, and pairing them by
      world bounding box (Hungarian assignment on the largest corner difference)
      leaves no pair whose corners differ by more than max(1.1 T, 1e-3 diag) (1.1 T
      for the reason given below: both meshes may stand that far apart). The
      number of placed parts (XCAF leaf placements) is printed beside it, so a part
      exported as one node for several solids is told from a missing placement.
  (a) every sample of our export (vertices, edge midpoints, centroids and
      area-weighted random points) lies within 1.1 T of OCCT's fine mesh;
  (b) every sample of OCCT's fine mesh lies within 1.1 T of our export (nothing
      missing).
  Why 1.1: our export promises to be within T of the true surface; OCCT's fine
  mesh is within T/10 of it (its linear deflection), so the honest bound between
  the two meshes is T + T/10 in both directions.
  Where OCCT gives one of its edges or vertices a tolerance beyond T, its B-rep is
  defined only to that tolerance around it: a sample of (a) or (b) within that
  tolerance of the edge or vertex (and, for (b), within it plus T of ours) is not
  counted, and the report says how many were left out (gen-14-37: a fillet edge of
  2.27 mm whose pcurve goes round a sphere's pole that its 3D curve passes by).

Distances (a) and (b) are measured to the whole placed scene of the other side
(not only to the paired instance), so they do not depend on how either side splits
parts into instances; (c) checks the instances. Each distance is first bounded
from above by the nearest point of a dense point set of the target (cKDTree);
only samples whose bound exceeds 0.25 T get an exact point-to-triangle distance
(trimesh.proximity.closest_point, in chunks of 2 000 points to bound memory). The
reported worst value is therefore exact where it matters (above 0.25 T) and an
upper bound below. Samples are capped per file (--max-samples) and the counts are
printed.

Where the worst sample of (a) or (b) lies is reported as the instance name, the
OCCT face (index in its part, surface type from BRepAdaptor_Surface.GetType with its
parameters: cone half-angle, radii, B-spline degrees and periodicity, parameter
ranges) and the world point. (OCCT's STEP transfer does not record which
ADVANCED_FACE became which face, so no #id is given.)

IGES files (.igs/.iges[.gz]) are read by OCCT's IGESControl_Reader and sewn with
BRepBuilderAPI_Sewing (class OcctIges): one part, one instance; compared exactly as above.

Exit status 1 on any failure not listed in --known-failures (lines `file: reason`;
listed files that fail print KNOWN, listed files that pass print FIXED (remove
from list)). `--self-test` checks the judge itself with mutated exports.
"""

import argparse
import glob
import gzip
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CHUNK = 2000
EXACT_BELOW = 0.25  # samples whose upper bound is <= EXACT_BELOW * T skip the exact query
BOUND = 1.1


def log(*a):
    print(*a, flush=True)


# ----------------------------------------------------------------------------- GLB


def _mat_from_node(n):
    if "matrix" in n:
        return np.array(n["matrix"], dtype=np.float64).reshape(4, 4).T  # column-major
    m = np.eye(4)
    if "scale" in n:
        m = np.diag(list(n["scale"]) + [1.0]) @ m
    if "rotation" in n:
        x, y, z, w = n["rotation"]
        r = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        rm = np.eye(4)
        rm[:3, :3] = r
        m = rm @ m
    if "translation" in n:
        t = np.eye(4)
        t[:3, 3] = n["translation"]
        m = t @ m
    return m


# y-up glTF to z-up millimetre scene: (x, y, z)_y -> (x, -z, y)_z
Y_TO_Z = np.array([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]], dtype=np.float64)


def _frame(extras, inherited):
    """Scale and axis change given by an extras dict {unit, up}; None if it says nothing."""
    if not isinstance(extras, dict) or ("unit" not in extras and "up" not in extras):
        return inherited
    unit = extras.get("unit", "mm")
    up = extras.get("up", "z")
    s = {"mm": 1.0, "m": 1000.0, "cm": 10.0, "in": 25.4}[unit]
    m = np.diag([s, s, s, 1.0])
    if up == "y":
        m = Y_TO_Z @ m
    elif up != "z":
        raise ValueError("unknown up axis %r" % up)
    return m


def read_glb(path):
    """Instances of a GLB: list of dicts {name, V (world mm, z-up), F}.

    World = frame(asset/node extras) x product of node matrices from the root."""
    b = open(path, "rb").read()
    magic, _ver, _len = struct.unpack("<4sII", b[:12])
    if magic != b"glTF":
        raise ValueError("%s is not a GLB" % path)
    off, js, binc = 12, None, b""
    while off < len(b):
        clen, ctype = struct.unpack("<II", b[off : off + 8])
        data = b[off + 8 : off + 8 + clen]
        if ctype == 0x4E4F534A:
            js = json.loads(data)
        elif ctype == 0x004E4942:
            binc = data
        off += 8 + clen
    comp = {5126: ("<f4", 4), 5125: ("<u4", 4), 5123: ("<u2", 2), 5121: ("u1", 1)}
    ncomp = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "VEC2": 2}

    def accessor(i):
        a = js["accessors"][i]
        bv = js["bufferViews"][a["bufferView"]]
        dt, sz = comp[a["componentType"]]
        k = ncomp[a["type"]]
        start = bv.get("byteOffset", 0) + a.get("byteOffset", 0)
        stride = bv.get("byteStride", 0) or sz * k
        cnt = a["count"]
        if stride == sz * k:
            arr = np.frombuffer(binc, dtype=dt, count=cnt * k, offset=start).reshape(cnt, k)
        else:
            raw = np.frombuffer(binc, dtype=np.uint8, count=stride * (cnt - 1) + sz * k, offset=start)
            arr = np.lib.stride_tricks.as_strided(raw, shape=(cnt, sz * k), strides=(stride, 1))
            arr = arr.copy().view(dt).reshape(cnt, k)
        return arr

    meshes = []
    for m in js.get("meshes", []):
        vs, fs, n = [], [], 0
        for p in m["primitives"]:
            if p.get("mode", 4) != 4:
                continue
            v = accessor(p["attributes"]["POSITION"]).astype(np.float64)
            f = accessor(p["indices"]).astype(np.int64).reshape(-1, 3) if "indices" in p else np.arange(len(v)).reshape(-1, 3)
            vs.append(v)
            fs.append(f + n)
            n += len(v)
        meshes.append((np.vstack(vs) if vs else np.zeros((0, 3)), np.vstack(fs) if fs else np.zeros((0, 3), np.int64)))
    root_frame = _frame(js.get("asset", {}).get("extras"), np.eye(4))
    out = []
    nodes = js.get("nodes", [])
    scene = js.get("scenes", [{}])[js.get("scene", 0)] if js.get("scenes") else {"nodes": list(range(len(nodes)))}

    def visit(i, parent, frame):
        n = nodes[i]
        fr = _frame(n.get("extras"), None)
        if fr is not None:  # a node's own {unit, up} applies to it and below it
            parent = parent @ fr
        w = parent @ _mat_from_node(n)
        if "mesh" in n:
            V, F = meshes[n["mesh"]]
            if len(F):
                Vw = V @ w[:3, :3].T + w[:3, 3]
                out.append({"name": n.get("name", "node %d" % i), "V": Vw, "F": F})
        for c in n.get("children", []):
            visit(c, w, frame)

    for r in scene.get("nodes", []):
        visit(r, root_frame, root_frame)
    return out


def write_glb(path, instances, asset_extras=None, parent_matrix=None):
    """Minimal GLB writer (used by --self-test): one mesh and one node per instance, all
    children of one root node carrying `parent_matrix` (4x4, applied to the children)."""
    bin_parts, views, accs, meshes, nodes = [], [], [], [], []
    off = 0
    inv = np.linalg.inv(parent_matrix) if parent_matrix is not None else np.eye(4)
    for k, ins in enumerate(instances):
        V = ins["V"] @ inv[:3, :3].T + inv[:3, 3]
        v = V.astype("<f4").tobytes()
        f = ins["F"].astype("<u4").tobytes()
        for data, target in ((v, 34962), (f, 34963)):
            pad = (-len(data)) % 4
            views.append({"buffer": 0, "byteOffset": off, "byteLength": len(data), "target": target})
            bin_parts.append(data + b"\0" * pad)
            off += len(data) + pad
        accs.append({"bufferView": 2 * k, "componentType": 5126, "count": len(V), "type": "VEC3",
                     "min": V.min(0).tolist(), "max": V.max(0).tolist()})
        accs.append({"bufferView": 2 * k + 1, "componentType": 5125, "count": ins["F"].size, "type": "SCALAR"})
        meshes.append({"name": ins["name"], "primitives": [{"attributes": {"POSITION": 2 * k}, "indices": 2 * k + 1}]})
        nodes.append({"name": ins["name"], "mesh": k})
    root = {"name": "root", "children": list(range(len(instances)))}
    if parent_matrix is not None:
        root["matrix"] = np.asarray(parent_matrix, dtype=np.float64).T.reshape(-1).tolist()
    nodes.append(root)
    binc = b"".join(bin_parts)
    asset = {"version": "2.0", "generator": "occt_fidelity self-test"}
    if asset_extras:
        asset["extras"] = asset_extras
    js = {"asset": asset, "scene": 0, "scenes": [{"nodes": [len(nodes) - 1]}], "nodes": nodes, "meshes": meshes,
          "accessors": accs, "bufferViews": views, "buffers": [{"byteLength": len(binc)}]}
    j = json.dumps(js).encode()
    j += b" " * ((-len(j)) % 4)
    total = 12 + 8 + len(j) + 8 + len(binc)
    with open(path, "wb") as fh:
        fh.write(struct.pack("<4sII", b"glTF", 2, total))
        fh.write(struct.pack("<II", len(j), 0x4E4F534A) + j)
        fh.write(struct.pack("<II", len(binc), 0x004E4942) + binc)


# ----------------------------------------------------------------------------- OCCT


class Occt:
    """One STEP file read through XCAF: prototypes (one per leaf part label) and placed
    instances (prototype index, sub-shape index, world 4x4, name)."""

    def __init__(self, path, built=None):
        """`built`: {part name: shape} of a generated model as OCCT built it; those parts are
        judged as built instead of as OCCT reads them back from the STEP it wrote (the round
        trip can change a face: seed 7 model 6, a sphere fused with a loft, read back with the
        hole in its face covered twice, 7 088 mm² of a 6 856 mm² sphere), and where the two
        differ `roundtrip` says so."""
        from OCP.IFSelect import IFSelect_RetDone
        from OCP.Interface import Interface_Static
        from OCP.STEPCAFControl import STEPCAFControl_Reader
        from OCP.TCollection import TCollection_ExtendedString
        from OCP.TDocStd import TDocStd_Document
        from OCP.TopLoc import TopLoc_Location
        from OCP.XCAFDoc import XCAFDoc_DocumentTool

        Interface_Static.SetCVal_s("xstep.cascade.unit", "MM")
        self.doc = TDocStd_Document(TCollection_ExtendedString("XmlOcaf"))
        try:
            from OCP.UnitsMethods import UnitsMethods_LengthUnit

            XCAFDoc_DocumentTool.SetLengthUnit_s(self.doc, 1.0, UnitsMethods_LengthUnit.UnitsMethods_LengthUnit_Millimeter)
        except Exception:
            pass
        self.reader = STEPCAFControl_Reader()
        self.reader.SetNameMode(True)
        if self.reader.ReadFile(path) != IFSelect_RetDone:
            raise RuntimeError("OCCT could not read " + path)
        if not self.reader.Transfer(self.doc):
            raise RuntimeError("OCCT could not transfer " + path)
        self.st = XCAFDoc_DocumentTool.ShapeTool_s(self.doc.Main())
        self.protos = []  # dict(label entry, name, shape, subs=[shapes], faces=[...])
        self.proto_of = {}
        self.instances = []  # dict(proto, sub, M (4x4), name)
        self.placements = 0  # placed leaf parts (an instance is a solid/shell of one)
        self.built = built or {}
        self.roundtrip = []  # parts whose read-back differs from the model built
        from OCP.OCP.collections import Sequence_TDF_Label

        free = Sequence_TDF_Label()
        self.st.GetFreeShapes(free)
        for i in range(1, free.Length() + 1):
            self._walk(free.Value(i), TopLoc_Location(), None)

    @staticmethod
    def _name(label):
        from OCP.TDataStd import TDataStd_Name

        n = TDataStd_Name()
        if label.FindAttribute(TDataStd_Name.GetID_s(), n):
            return n.Get().ToExtString()
        return ""

    @staticmethod
    def _entry(label):
        from OCP.TCollection import TCollection_AsciiString
        from OCP.TDF import TDF_Tool

        s = TCollection_AsciiString()
        TDF_Tool.Entry_s(label, s)
        return s.ToCString()

    def _walk(self, label, loc, inst_name):
        from OCP.OCP.collections import Sequence_TDF_Label
        from OCP.TDF import TDF_Label
        from OCP.XCAFDoc import XCAFDoc_ShapeTool as S

        if S.IsAssembly_s(label):
            comps = Sequence_TDF_Label()
            S.GetComponents_s(label, comps, False)
            for i in range(1, comps.Length() + 1):
                c = comps.Value(i)
                ref = TDF_Label()
                S.GetReferredShape_s(c, ref)
                self._walk(ref, loc.Multiplied(S.GetLocation_s(c)), self._name(c) or None)
            return
        key = self._entry(label)
        if key not in self.proto_of:
            shape = S.GetShape_s(label)
            name = self._name(label) or key
            if name in self.built:
                shape = self._as_built(name, shape, self.built[name])
            self.proto_of[key] = len(self.protos)
            self.protos.append({"name": self._name(label) or key, "shape": shape, "subs": self._leaves(shape)})
        p = self.proto_of[key]
        self.placements += 1
        M = _loc_matrix(loc)
        for k in range(len(self.protos[p]["subs"])):
            self.instances.append({"proto": p, "sub": k, "M": M, "name": self.protos[p]["name"]})

    def _as_built(self, name, read, built):
        """The part as built, noting in `roundtrip` where the read-back differs from it (its
        area or its box by more than 0.1 % of the box's diagonal)."""
        from OCP.BRepGProp import BRepGProp
        from OCP.GProp import GProp_GProps

        def area(sh):
            g = GProp_GProps()
            BRepGProp.SurfaceProperties_s(sh, g)
            return g.Mass()

        def box(sh):
            from OCP.Bnd import Bnd_Box
            from OCP.BRepBndLib import BRepBndLib

            b = Bnd_Box()
            BRepBndLib.AddOptimal_s(sh, b, False, False)
            if b.IsVoid():
                return np.zeros(6)
            return np.array(b.CornerMin().Coord() + b.CornerMax().Coord())

        a0, a1 = area(built), area(read)
        b0, b1 = box(built), box(read)
        diag = float(np.linalg.norm(b0[3:] - b0[:3]))
        if abs(a0 - a1) > 1e-3 * max(a0, 1e-12) or float(np.abs(b0 - b1).max()) > 1e-3 * diag:
            self.roundtrip.append("%s: built %.6g mm² (box %s), read back from the STEP %.6g mm² (box %s)" % (
                name, a0, np.round(b0, 3).tolist(), a1, np.round(b1, 3).tolist()))
        return built

    @staticmethod
    def _leaves(shape):
        """Solids, shells outside solids, and (as one compound) faces outside shells."""
        from OCP.BRep import BRep_Builder
        from OCP.TopAbs import TopAbs_FACE, TopAbs_SHELL, TopAbs_SOLID
        from OCP.TopExp import TopExp_Explorer
        from OCP.TopoDS import TopoDS_Compound

        subs = []
        e = TopExp_Explorer(shape, TopAbs_SOLID)
        while e.More():
            subs.append(e.Current())
            e.Next()
        e = TopExp_Explorer(shape, TopAbs_SHELL, TopAbs_SOLID)
        while e.More():
            subs.append(e.Current())
            e.Next()
        e = TopExp_Explorer(shape, TopAbs_FACE, TopAbs_SHELL)
        loose = []
        while e.More():
            loose.append(e.Current())
            e.Next()
        if loose:
            b, c = BRep_Builder(), TopoDS_Compound()
            b.MakeCompound(c)
            for f in loose:
                b.Add(c, f)
            subs.append(c)
        return subs

    def face_count(self):
        return sum(len(p.get("faces", [])) or _count_faces(p["shape"]) for p in self.protos)

    def bbox(self):
        """World bounding box from the B-rep (no mesh needed)."""
        from OCP.Bnd import Bnd_Box
        from OCP.BRepBndLib import BRepBndLib

        lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
        cache = {}
        for ins in self.instances:
            key = (ins["proto"], ins["sub"])
            if key not in cache:
                b = Bnd_Box()
                BRepBndLib.Add_s(self.protos[ins["proto"]]["subs"][ins["sub"]], b, False)
                if b.IsVoid():
                    cache[key] = None
                    continue
                (x0, y0, z0), (x1, y1, z1) = b.CornerMin().Coord(), b.CornerMax().Coord()
                cache[key] = np.array([[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)])
            c = cache[key]
            if c is None:
                continue
            w = c @ ins["M"][:3, :3].T + ins["M"][:3, 3]
            lo, hi = np.minimum(lo, w.min(0)), np.maximum(hi, w.max(0))
        return lo, hi

    def mesh(self, deflection):
        """Mesh every prototype at `deflection`; per instance world V, F and per-triangle
        face index (in the prototype's face list)."""
        from OCP.BRep import BRep_Tool
        from OCP.BRepMesh import BRepMesh_IncrementalMesh
        from OCP.BRepTools import BRepTools
        from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
        from OCP.TopExp import TopExp_Explorer
        from OCP.TopLoc import TopLoc_Location
        from OCP.TopoDS import TopoDS

        local = {}
        self.unmeshed = []  # (prototype, face) that BRepMesh left without triangles
        for pi, p in enumerate(self.protos):
            BRepTools.Clean_s(p["shape"])
            BRepMesh_IncrementalMesh(p["shape"], deflection, False, 0.5, True)
            faces, findex = [], {}
            e = TopExp_Explorer(p["shape"], TopAbs_FACE)
            while e.More():
                f = e.Current()
                faces.append(f)
                e.Next()
            p["faces"] = faces
            for si, sub in enumerate(p["subs"]):
                Vs, Fs, Ids, Std, n = [], [], [], [], 0
                e = TopExp_Explorer(sub, TopAbs_FACE)
                while e.More():
                    f = TopoDS.Face(e.Current())
                    e.Next()
                    fid = _face_index(faces, f)
                    floc = TopLoc_Location()
                    tri = BRep_Tool.Triangulation_s(f, floc)
                    if tri is None or tri.NbTriangles() == 0:
                        # BRepMesh failed on this face: stand in with points sampled on the face
                        # (as zero-area triangles, so they serve as samples and kd-tree points)
                        self.unmeshed.append((pi, fid))
                        V = _face_points(f, deflection * 3)
                        if len(V):
                            Vs.append(V)
                            Fs.append(np.repeat(np.arange(len(V))[:, None], 3, axis=1) + n)
                            Ids.append(np.full(len(V), fid))
                            Std.append(np.ones(len(V), bool))
                            n += len(V)
                        continue
                    nn = tri.NbNodes()
                    V = np.array([tri.Node(i).Coord() for i in range(1, nn + 1)], dtype=np.float64)
                    if not floc.IsIdentity():
                        Mf = _loc_matrix(floc)
                        V = V @ Mf[:3, :3].T + Mf[:3, 3]
                    F = np.array([tri.Triangle(i).Get() for i in range(1, tri.NbTriangles() + 1)], dtype=np.int64) - 1
                    if f.Orientation() == TopAbs_REVERSED:
                        F = F[:, ::-1]
                    Vs.append(V)
                    Fs.append(F + n)
                    Ids.append(np.full(len(F), fid))
                    Std.append(np.zeros(len(F), bool))
                    n += len(V)
                local[(pi, si)] = (
                    np.vstack(Vs) if Vs else np.zeros((0, 3)),
                    np.vstack(Fs) if Fs else np.zeros((0, 3), np.int64),
                    np.concatenate(Ids) if Ids else np.zeros(0, np.int64),
                    np.concatenate(Std) if Std else np.zeros(0, bool),
                )
        out = []
        for ins in self.instances:
            V, F, ids, std = local[(ins["proto"], ins["sub"])]
            M = ins["M"]
            out.append({"name": ins["name"], "V": V @ M[:3, :3].T + M[:3, 3], "F": F, "face": ids, "standin": std, "proto": ins["proto"],
                        "sub": ins["sub"], "M": M})
        return out

    @staticmethod
    def _in_part(ins, point):
        """A world point in the frame of instance `ins`'s part: its coordinates and a vertex
        there (for BRepExtrema)."""
        from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
        from OCP.gp import gp_Pnt

        M = ins["M"]
        q = np.linalg.solve(M[:3, :3], np.asarray(point, dtype=np.float64) - M[:3, 3])
        return q, BRepBuilderAPI_MakeVertex(gp_Pnt(*q.tolist())).Vertex()

    def brep_distance(self, ins, point, far=float("inf")):
        """Exact distance from a world point to an instance's B-rep (BRepExtrema); where that
        exceeds `far`, also to the faces' surfaces at feet inside the faces (see
        `_surface_distance`)."""
        from OCP.BRepExtrema import BRepExtrema_DistShapeShape

        q, v = self._in_part(ins, point)
        shape = self._boundary(ins["proto"], ins["sub"])
        d = BRepExtrema_DistShapeShape(v, shape)
        best = d.Value() if d.IsDone() else float("nan")
        if not best <= far:  # also when BRepExtrema failed (nan)
            best = min(best if best == best else np.inf, self._surface_distance(ins["proto"], q, best))
        return best

    def _surface_distance(self, proto, q, beyond):
        """Distance from q (the part's frame) to the faces' surfaces at feet that OCCT's face
        classifier puts in or on the face (pcurves, 2D tolerance 1e-6 of the face's parameter
        span): BRepExtrema falls back on the 3D edges for a foot just outside a face, and a
        face whose 3D edge stops short of its pcurve (gen-1-78: OCCT's offset of a box, a line
        edge ending at a vertex 20 off the circle it meets, its tolerance grown to 20.1) then
        puts a point on the face's border 1.5 mm away from it. Only faces whose box lies within
        `beyond` of q are tried."""
        from OCP.Bnd import Bnd_Box
        from OCP.BRep import BRep_Tool
        from OCP.BRepBndLib import BRepBndLib
        from OCP.BRepClass import BRepClass_FaceClassifier
        from OCP.BRepTools import BRepTools
        from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
        from OCP.TopAbs import TopAbs_IN, TopAbs_ON
        from OCP.TopoDS import TopoDS
        from OCP.gp import gp_Pnt, gp_Pnt2d

        p = gp_Pnt(*q.tolist())
        best = float("inf")
        for f in self.protos[proto]["faces"]:
            face = TopoDS.Face(f)
            b = Bnd_Box()
            BRepBndLib.Add_s(face, b, False)
            if b.IsVoid() or b.Distance(Bnd_Box(p, p)) > beyond:
                continue
            surf = BRep_Tool.Surface_s(face)
            proj = GeomAPI_ProjectPointOnSurf(p, surf)
            if proj.NbPoints() == 0 or proj.LowerDistance() >= best:
                continue
            u, v = proj.LowerDistanceParameters()
            u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
            tol = 1e-6 * max(u1 - u0, v1 - v0, 1e-12)
            state = BRepClass_FaceClassifier(face, gp_Pnt2d(u, v), tol).State()
            if state in (TopAbs_IN, TopAbs_ON):
                best = proj.LowerDistance()
        return best

    def exact_world_box(self, ins):
        """Tight box (BRepBndLib.AddOptimal, no triangulation, no tolerances) of an instance's
        faces placed in the world: what check c falls back on where OCCT's own mesh strays
        off its B-rep (a rational sweep's BRepMesh left points 0.74 mm off it)."""
        from OCP.Bnd import Bnd_Box
        from OCP.BRepBndLib import BRepBndLib
        from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
        from OCP.gp import gp_Trsf

        M = ins["M"]
        tr = gp_Trsf()
        tr.SetValues(*[float(M[i, j]) for i in range(3) for j in range(4)])
        moved = BRepBuilderAPI_Transform(self._boundary(ins["proto"], ins["sub"]), tr, True).Shape()
        b = Bnd_Box()
        BRepBndLib.AddOptimal_s(moved, b, False, False)
        if b.IsVoid():
            return np.full(6, np.nan)
        return np.array(b.CornerMin().Coord() + b.CornerMax().Coord())

    def _boundary(self, proto, sub):
        """The faces of a leaf shape as one compound: the distance to a *solid* is 0 for any
        point inside it (BRepExtrema's inner solution), which would take a chord through the
        solid for a point on its B-rep."""
        from OCP.BRep import BRep_Builder
        from OCP.TopAbs import TopAbs_FACE
        from OCP.TopExp import TopExp_Explorer
        from OCP.TopoDS import TopoDS_Compound

        cache = self.__dict__.setdefault("_boundaries", {})
        if (proto, sub) not in cache:
            shape = self.protos[proto]["subs"][sub]
            comp, builder = TopoDS_Compound(), BRep_Builder()
            builder.MakeCompound(comp)
            ex = TopExp_Explorer(shape, TopAbs_FACE)
            while ex.More():
                builder.Add(comp, ex.Current())
                ex.Next()
            cache[(proto, sub)] = comp
        return cache[(proto, sub)]

    def tolerant(self, proto, sub, T):
        """The edges and vertices of a leaf shape to which OCCT gives a tolerance beyond T, as
        (tolerance, shape), largest first: where its B-rep is defined only to that tolerance."""
        from OCP.BRep import BRep_Tool
        from OCP.TopAbs import TopAbs_EDGE, TopAbs_VERTEX
        from OCP.TopExp import TopExp_Explorer
        from OCP.TopoDS import TopoDS

        cache = self.__dict__.setdefault("_tolerant", {})
        if (proto, sub) not in cache:
            found = []
            for kind, cast in ((TopAbs_EDGE, TopoDS.Edge), (TopAbs_VERTEX, TopoDS.Vertex)):
                e = TopExp_Explorer(self.protos[proto]["subs"][sub], kind)
                while e.More():
                    found.append((BRep_Tool.Tolerance_s(cast(e.Current())), e.Current()))
                    e.Next()
            cache[(proto, sub)] = sorted(found, key=lambda x: -x[0])
        return [(t, sh) for t, sh in cache[(proto, sub)] if t > T]

    def within_tolerance(self, ins, point, d, T):
        """The tolerance of the edge or vertex of instance `ins` in whose tolerance tube the
        world `point` lies, when `d` (its distance from OCCT's B-rep, or from ours for a sample
        of OCCT's) is within that tolerance plus T; else None. OCCT's B-rep is defined only to
        an edge's tolerance around it (gen-14-37: a fillet edge carries 2.27 mm as built, 0.88
        read back, and its pcurve on a sphere goes round the pole its 3D curve passes 0.44 mm
        from: a point within it and 0.44 mm from the face is no evidence of a fault)."""
        from OCP.BRepExtrema import BRepExtrema_DistShapeShape

        near = [(t, sh) for t, sh in self.tolerant(ins["proto"], ins["sub"], T) if d <= t + T]
        if not near:
            return None
        _, v = self._in_part(ins, point)
        for t, sh in near:
            x = BRepExtrema_DistShapeShape(v, sh)
            if x.IsDone() and x.Value() <= t:
                return t
        return None

    def excuse_tolerance(self, occt_fine, inst_of, P, d, idx, T):
        """Sets to 0 the distances `d[idx]` of samples `P[idx]` (of OCCT instances
        `inst_of[idx]`) that lie within OCCT's tolerance of an edge or vertex
        (`within_tolerance`). Returns how many, and the largest tolerance that excused one."""
        n, worst = 0, 0.0
        for i in idx:
            if d[i] <= BOUND * T:
                continue
            t = self.within_tolerance(occt_fine[inst_of[i]], P[i], d[i], T)
            if t is not None:
                d[i] = 0.0
                n, worst = n + 1, max(worst, t)
        return n, worst

    def describe_face(self, proto, fid):
        from OCP.BRepAdaptor import BRepAdaptor_Surface

        from OCP.TopoDS import TopoDS

        p = self.protos[proto]
        f = TopoDS.Face(p["faces"][fid])
        typ = str(BRepAdaptor_Surface(f).GetType()).split(".")[-1].replace("GeomAbs_", "")
        ent = ""
        try:
            a = BRepAdaptor_Surface(f)
            if typ == "Cone":
                c = a.Cone()
                ent = "(half-angle %.4g deg, r %.4g)" % (np.degrees(c.SemiAngle()), c.RefRadius())
            elif typ == "Cylinder":
                ent = "(r %.4g)" % a.Cylinder().Radius()
            elif typ == "Sphere":
                ent = "(r %.4g)" % a.Sphere().Radius()
            elif typ == "Torus":
                t = a.Torus()
                ent = "(R %.4g, r %.4g)" % (t.MajorRadius(), t.MinorRadius())
            elif typ == "BSplineSurface":
                ent = "(deg %d x %d, %s%s)" % (a.UDegree(), a.VDegree(), "rational " if a.IsURational() or a.IsVRational() else "",
                                                "periodic U/V %d/%d" % (a.IsUPeriodic(), a.IsVPeriodic()))
            elif typ in ("SurfaceOfRevolution", "SurfaceOfExtrusion"):
                ent = "(basis curve %s)" % str(a.BasisCurve().GetType()).split(".")[-1].replace("GeomAbs_", "")
            elif typ == "OffsetSurface":
                ent = "(offset %.4g)" % a.OffsetValue()
            u0, u1, v0, v1 = a.FirstUParameter(), a.LastUParameter(), a.FirstVParameter(), a.LastVParameter()
            ent += " u %.4g..%.4g v %.4g..%.4g" % (u0, u1, v0, v1)
        except Exception:  # noqa: BLE001
            pass
        ent = " " + ent if ent else ""
        return "%s face %d %s%s" % (p["name"], fid, typ, ent)


class OcctIges(Occt):
    """One IGES file read as OCCT users do: IGESControl_Reader (lengths in mm), every root
    transferred into one shape, the faces sewn with BRepBuilderAPI_Sewing (its default
    tolerance). IGES keeps no assembly structure that the reader passes on: the sewn shape is
    one part with one instance, as patchwork exports an IGES file's faces as one mesh."""

    def __init__(self, path):
        from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing
        from OCP.IFSelect import IFSelect_RetDone
        from OCP.IGESControl import IGESControl_Reader
        from OCP.Interface import Interface_Static

        Interface_Static.SetCVal_s("xstep.cascade.unit", "MM")
        reader = IGESControl_Reader()
        if reader.ReadFile(path) != IFSelect_RetDone:
            raise RuntimeError("OCCT could not read " + path)
        if reader.TransferRoots() == 0:
            raise RuntimeError("OCCT transferred nothing from " + path)
        sewing = BRepBuilderAPI_Sewing()
        sewing.Add(reader.OneShape())
        sewing.Perform()
        shape = sewing.SewedShape()
        name = os.path.basename(path)
        self.protos = [{"name": name, "shape": shape, "subs": [shape]}]
        self.proto_of = {name: 0}
        self.instances = [{"proto": 0, "sub": 0, "M": np.eye(4), "name": name}]
        self.placements = 1


def is_iges(path):
    p = path.lower()
    return p.endswith((".igs", ".iges", ".igs.gz", ".iges.gz"))


def _face_points(face, spacing, cap=200000):
    """Points on a face (its surface inside its boundary) about `spacing` apart."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepTools import BRepTools
    from OCP.BRepClass import BRepClass_FaceClassifier
    from OCP.gp import gp_Pnt2d
    from OCP.TopAbs import TopAbs_IN, TopAbs_ON

    a = BRepAdaptor_Surface(face)
    u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
    g = 9
    P = np.array([[a.Value(u, v).Coord() for v in np.linspace(v0, v1, g)] for u in np.linspace(u0, u1, g)])
    lu = np.linalg.norm(np.diff(P, axis=0), axis=2).sum(0).max()
    lv = np.linalg.norm(np.diff(P, axis=1), axis=2).sum(1).max()
    nu = int(np.clip(np.ceil(lu / spacing), 2, 2000))
    nv = int(np.clip(np.ceil(lv / spacing), 2, 2000))
    while nu * nv > cap:
        nu, nv = max(2, nu * 3 // 4), max(2, nv * 3 // 4)
    cls = BRepClass_FaceClassifier()
    out = []
    for u in np.linspace(u0, u1, nu):
        for v in np.linspace(v0, v1, nv):
            cls.Perform(face, gp_Pnt2d(u, v), 1e-7)
            if cls.State() in (TopAbs_IN, TopAbs_ON):
                out.append(a.Value(u, v).Coord())
    return np.array(out, dtype=np.float64).reshape(-1, 3)


def _face_index(faces, f):
    for i, g in enumerate(faces):
        if g.IsSame(f):
            return i
    return -1


def _count_faces(shape):
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer

    n, e = 0, TopExp_Explorer(shape, TopAbs_FACE)
    while e.More():
        n += 1
        e.Next()
    return n


def _loc_matrix(loc):
    t = loc.Transformation()
    M = np.eye(4)
    for r in range(3):
        for c in range(4):
            M[r, c] = t.Value(r + 1, c + 1)
    return M


# ----------------------------------------------------------------------------- geometry


def concat(instances, with_face=False):
    Vs, Fs, inst, face, n = [], [], [], [], 0
    for k, ins in enumerate(instances):
        Vs.append(ins["V"])
        Fs.append(ins["F"] + n)
        inst.append(np.full(len(ins["F"]), k))
        if with_face:
            face.append(ins["face"])
        n += len(ins["V"])
    V = np.vstack(Vs) if Vs else np.zeros((0, 3))
    F = np.vstack(Fs) if Fs else np.zeros((0, 3), np.int64)
    I = np.concatenate(inst) if inst else np.zeros(0, np.int64)
    Fa = np.concatenate(face) if with_face and face else None
    return V, F, I, Fa


def sample(V, F, cap, per_tri, rng):
    """Points on a mesh and the triangle each lies on: vertices, edge midpoints, centroids
    and area-weighted random points (per_tri per triangle), subsampled to `cap`."""
    if len(F) == 0:
        return np.zeros((0, 3)), np.zeros(0, np.int64)
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(B - A, C - A), axis=1)
    tri_of_vertex = np.full(len(V), -1, np.int64)
    tri_of_vertex[F.ravel()] = np.repeat(np.arange(len(F)), 3)
    used = np.nonzero(tri_of_vertex >= 0)[0]
    base_p = [V[used], (A + B) / 2, (B + C) / 2, (C + A) / 2, (A + B + C) / 3]
    base_t = [tri_of_vertex[used]] + [np.arange(len(F))] * 4
    P, T = np.vstack(base_p), np.concatenate(base_t)
    nrand = max(0, min(per_tri * len(F), cap - len(P)))
    if len(P) > cap:  # huge file: keep a random subset of the structured samples
        keep = rng.choice(len(P), size=cap * 2 // 3, replace=False)
        P, T = P[keep], T[keep]
        nrand = cap - len(P)
    if nrand > 0 and area.sum() > 0:
        t = rng.choice(len(F), size=nrand, p=area / area.sum())
        r1, r2 = rng.random(nrand), rng.random(nrand)
        s = np.sqrt(r1)
        R = (1 - s)[:, None] * A[t] + (s * (1 - r2))[:, None] * B[t] + (s * r2)[:, None] * C[t]
        P, T = np.vstack([P, R]), np.concatenate([T, t])
    return P, T


class Target:
    """A mesh to measure distances to: exact closest point (trimesh) after a cKDTree
    upper bound on a dense point set of the mesh."""

    def __init__(self, V, F, T, rng):
        import trimesh
        from scipy.spatial import cKDTree

        A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
        area2 = np.linalg.norm(np.cross(B - A, C - A), axis=1)
        good = area2 > 1e-14 * max(1.0, float(np.abs(V).max()) if len(V) else 1.0) ** 2
        self.tri_map = np.nonzero(good)[0]
        self.mesh = trimesh.Trimesh(vertices=V, faces=F[good], process=False, validate=False)
        # dense point set for the upper bound: samples about T/2 apart plus the structured ones
        area = 0.5 * area2.sum()
        n = int(min(4e6, max(0, area / (0.5 * T) ** 2)))
        P, Tr = sample(V, F, cap=max(n, 1), per_tri=0, rng=rng)
        if n > 0:
            t = rng.choice(len(F), size=n, p=area2 / area2.sum())
            r1, r2 = rng.random(n), rng.random(n)
            s = np.sqrt(r1)
            R = (1 - s)[:, None] * A[t] + (s * (1 - r2))[:, None] * B[t] + (s * r2)[:, None] * C[t]
            P, Tr = np.vstack([P, R]), np.concatenate([Tr, t])
        self.pts_tri = Tr
        self.kd = cKDTree(P)

    def distance(self, P, T):
        """Distance (exact above EXACT_BELOW*T, an upper bound below) and the target triangle."""
        import trimesh

        if len(P) == 0:
            return np.zeros(0), np.zeros(0, np.int64), 0
        d, idx = self.kd.query(P, workers=1)
        tri = self.pts_tri[idx]
        need = np.nonzero(d > EXACT_BELOW * T)[0]
        for s in range(0, len(need), CHUNK):
            sel = need[s : s + CHUNK]
            _, dist, tid = trimesh.proximity.closest_point(self.mesh, P[sel])
            ok = np.isfinite(dist)
            d[sel[ok]] = np.minimum(d[sel[ok]], dist[ok])
            tri[sel[ok]] = np.where(dist[ok] <= d[sel[ok]], self.tri_map[tid[ok]], tri[sel[ok]])
        return d, tri, len(need)


def bbox_of(ins):
    return np.concatenate([ins["V"].min(0), ins["V"].max(0)]) if len(ins["V"]) else np.full(6, np.nan)


def match_instances(ours, theirs, tol):
    """Pair instances by world bbox; return (pairs, worst corner diff, mismatches)."""
    from scipy.optimize import linear_sum_assignment

    a = np.array([bbox_of(i) for i in ours]).reshape(-1, 6)
    b = np.array([bbox_of(i) for i in theirs]).reshape(-1, 6)
    if len(a) == 0 or len(b) == 0:
        return [], np.inf, []
    cost = np.abs(a[:, None, :] - b[None, :, :]).max(2)
    cost = np.nan_to_num(cost, nan=1e30)
    r, c = linear_sum_assignment(cost)
    pairs = list(zip(r.tolist(), c.tolist(), cost[r, c].tolist()))
    bad = [(i, j, x) for i, j, x in pairs if x > tol]
    return pairs, (max(x for _, _, x in pairs) if pairs else np.inf), bad


# ----------------------------------------------------------------------------- one file


def patchwork_cmd(pw, args, path, gz_plain):
    """Run patchwork on `path`; if it is a .gz that patchwork refuses, on the plain copy."""
    r = subprocess.run([pw] + args[:1] + [path] + args[1:], capture_output=True, text=True)
    if r.returncode != 0 and gz_plain and path != gz_plain:
        r = subprocess.run([pw] + args[:1] + [gz_plain] + args[1:], capture_output=True, text=True)
    return r


def our_stats(pw, path, plain, T):
    """`patchwork stats --tolerance T --json`: our own measure of the mesh that `export
    --tolerance T` writes (the same tessellation), to be set beside the judge's verdict (item 4
    of issue 29: the measure must fail exactly when the judge does). None if stats fails."""
    r = patchwork_cmd(pw, ["stats", "--tolerance", repr(T), "--json", "-q", "--faces", "3"], path, plain)
    if r.returncode != 0:
        return {"error": (r.stderr.strip().splitlines() or ["?"])[-1]}
    try:
        d = json.loads(r.stdout)
    except ValueError as e:
        return {"error": "stats printed no JSON (%s)" % e}
    t = d.get("trimmed") or {}
    worst = (t.get("worst_faces") or [{}])[0]
    return {
        "patches": d.get("patches"),
        "ratio": t.get("error_ratio", d.get("worst_error_ratio")),
        "worst_face": ("#%s %s" % (worst["face"], worst["surface"])) if worst else None,
        "outside": t.get("outside", 0),
        "skipped": len(d.get("skipped_faces") or []),
        "budget_stops": d.get("budget_stops", 0),
    }


# A file the judge fails has a sample beyond this many T; `stats` says the same of a file
# whose trimmed error/eps exceeds it (both bounds allow the T/10 of OCCT's fine mesh).
AGREE = 1.1


def judge_bad(r):
    """The judge found samples beyond 1.1 T (either direction) or there was no export."""
    return any(r.get(k) is None or r[k] > AGREE for k in ("a_over_T", "b_over_T"))


def stats_bad(r):
    s = r.get("stats") or {}
    return "error" in s or s.get("ratio") is None or s["ratio"] > AGREE or s.get("skipped", 0) > 0


def print_agreement(rows, known=()):
    """Item 4's table: the judge and `stats` at the same tolerance, on the same files. Returns
    the number of disagreements on files not listed in `known` (a listed failure of the judge
    is expected to disagree)."""
    rows = [r for r in rows if r.get("stats") is not None]
    if not rows:
        return
    cells = {(False, False): [], (True, True): [], (True, False): [], (False, True): []}
    for r in rows:
        cells[(judge_bad(r), stats_bad(r))].append(r)
    log("agreement of `stats --tolerance T` with the judge (bad: judge > %.1f T; stats trimmed error/eps > %.1f or a "
        "skipped face): both pass %d, both fail %d, judge only %d, stats only %d" % (
            AGREE, AGREE, len(cells[(False, False)]), len(cells[(True, True)]), len(cells[(True, False)]),
            len(cells[(False, True)])))
    for key, what in (((True, False), "judge only"), ((False, True), "stats only")):
        for r in cells[key]:
            s = r["stats"]
            log("    %s: %s @ rel %g: judge a %s b %s; stats %s" % (
                what, os.path.basename(r["file"]), r["rel"],
                "-" if r.get("a_over_T") is None else "%.2f T" % r["a_over_T"],
                "-" if r.get("b_over_T") is None else "%.2f T" % r["b_over_T"],
                s.get("error") or "error/eps %.3f (%s), %d outside, %d skipped" % (
                    s["ratio"] or 0.0, s.get("worst_face"), s.get("outside", 0), s.get("skipped", 0))))
    listed = lambda r: os.path.basename(r["file"]) in known or os.path.relpath(r["file"], REPO) in known  # noqa: E731
    return sum(1 for k in ((True, False), (False, True)) for r in cells[k] if not listed(r))


VERIFY = 4000  # exceeding samples per direction checked on the exact B-rep
VERIFY_ALL = 40000  # ... and all of them, up to this many, when the first VERIFY all lie on it


def verify_exact(occt, occt_fine, P, d, idx, far):
    """Exact distances from the points P[idx] to OCCT's B-rep (the instances whose bounding
    box, grown by the mesh distance, holds the point)."""
    boxes = [(bbox_of(i), i) for i in occt_fine if len(i["V"])]
    out = np.empty(len(idx))
    for n, k in enumerate(idx):
        p, r = P[k], d[k] * 1.01 + 1e-9
        best = np.inf
        for b, ins in boxes:
            if np.all(p >= b[:3] - r) and np.all(p <= b[3:] + r):
                best = min(best, occt.brep_distance(ins, p, far))
        out[n] = best
    return out


def evaluate(occt, ours, rel, T, diag, occt_fine, rng, max_samples, per_tri):
    """All checks for one file at one tolerance. Returns a result dict (without timing)."""
    res = {"rel": rel, "T": T, "inst_ours": len(ours), "inst_occt": len(occt_fine), "fail": []}
    tolbox = max(BOUND * T, 1e-3 * diag)  # both meshes are within 1.1 T of each other
    pairs, worst_box, bad = match_instances(ours, occt_fine, tolbox)
    if bad:  # OCCT's mesh box may be the one that is off: judge ours by OCCT's exact box too
        exact = {}
        for i, j, x in bad:
            try:
                exact[(i, j)] = float(np.abs(bbox_of(ours[i]) - occt.exact_world_box(occt_fine[j])).max())
            except Exception:  # noqa: BLE001 (a placement OCCT cannot take: keep the mesh's verdict)
                pass
        pairs = [(i, j, min(x, exact.get((i, j), x))) for i, j, x in pairs]
        res["bbox_exact_excused"] = len(bad) - sum(x > tolbox for _, _, x in pairs)
        bad = [p for p in pairs if p[2] > tolbox]
        worst_box = max(x for _, _, x in pairs)
    res["bbox_worst_over_T"] = worst_box / T if np.isfinite(worst_box) else None
    res["bbox_mismatch"] = len(bad) + abs(len(ours) - len(occt_fine))
    if len(ours) != len(occt_fine):
        res["fail"].append("c: %d instances ours vs %d OCCT" % (len(ours), len(occt_fine)))
        # which OCCT instances are unpaired / which of ours
        po = {i for i, _, _ in pairs}
        pt = {j for _, j, _ in pairs}
        extra = [ours[i]["name"] for i in range(len(ours)) if i not in po][:5]
        miss = [occt_fine[j]["name"] for j in range(len(occt_fine)) if j not in pt][:5]
        if extra:
            res["fail"][-1] += "; unpaired ours: " + ", ".join(extra)
        if miss:
            res["fail"][-1] += "; unpaired OCCT: " + ", ".join(miss)
    if bad:
        i, j, x = max(bad, key=lambda t: t[2])
        res["fail"].append("c: %d bbox mismatches, worst %s vs OCCT %s off by %.3g mm (%.2f T)" % (
            len(bad), ours[i]["name"], occt_fine[j]["name"], x, x / T))
    Vo, Fo, Io, _ = concat(ours)
    Vt, Ft, It, Fat = concat(occt_fine, with_face=True)
    if len(Fo) == 0 or len(Ft) == 0:
        res["fail"].append("empty mesh: ours %d triangles, OCCT %d" % (len(Fo), len(Ft)))
        return res
    res["tri_ours"], res["tri_occt"] = int(len(Fo)), int(len(Ft))
    # (a) ours -> OCCT
    Pa, Ta = sample(Vo, Fo, max_samples, per_tri, rng)
    tgt_t = Target(Vt, Ft, T, rng)
    da, tria, na = tgt_t.distance(Pa, T)
    k = int(np.argmax(da))
    res["samples_a"], res["exact_a"] = int(len(Pa)), int(na)
    res["a_over_T"] = float(da[k] / T)
    ti = int(tria[k])
    res["a_where"] = "%s near %s at (%.4g, %.4g, %.4g)" % (
        ours[Io[Ta[k]]]["name"], occt.describe_face(occt_fine[It[ti]]["proto"], int(Fat[ti])), *Pa[k])
    res["a_exceed"] = int((da > BOUND * T).sum())
    res["occt_unmeshed_faces"] = len(occt.unmeshed)
    if res["a_exceed"]:
        # OCCT's mesh may have holes (a face BRepMesh could not mesh): check the worst
        # exceeding samples on the exact B-rep and keep the exact distance for them.
        over = np.nonzero(da > BOUND * T)[0]
        order = over[np.argsort(-da[over])]
        chk = order[:VERIFY]
        ex = verify_exact(occt, occt_fine, Pa, da, chk, 0.1 * T)
        if len(order) > VERIFY and (ex <= BOUND * T).all():
            # Every one of the worst lies on the B-rep: a hole in OCCT's mesh, not in ours
            # (a face BRepMesh left unmeshed has thousands of our samples in it: seed 14 model
            # 37's sphere, 6 588 of them). The rest are checked too, up to VERIFY_ALL.
            chk = order[:VERIFY_ALL]
            ex = np.concatenate([ex, verify_exact(occt, occt_fine, Pa, da, chk[VERIFY:], 0.1 * T)])
        res["a_verified"] = int(len(chk))
        res["a_mesh_over_T"] = res["a_over_T"]
        res["a_false"] = int((ex <= BOUND * T).sum())  # on the B-rep although far from OCCT's mesh
        da[chk] = np.minimum(da[chk], ex)
        n, t = occt.excuse_tolerance(occt_fine, It[tria], Pa, da, chk, T)
        res["a_exceed"] = int((da > BOUND * T).sum())  # unchecked ones stay counted
        k = int(np.argmax(da))
        res["a_over_T"] = float(da[k] / T)
        ti = int(tria[k])
        res["a_where"] = "%s near %s at (%.4g, %.4g, %.4g)" % (
            ours[Io[Ta[k]]]["name"], occt.describe_face(occt_fine[It[ti]]["proto"], int(Fat[ti])), *Pa[k])
        res["a_where"] += " [checked %d samples on the exact B-rep: %d lie on it (OCCT mesh hole)]" % (len(chk), res["a_false"])
        if n:
            res["a_tolerance"] = n
            res["a_where"] += " [%d samples within OCCT's own tolerance of an edge or vertex (up to %.3g mm), not counted]" % (n, t)
    if occt.unmeshed:
        res["fail_note"] = "OCCT's BRepMesh left %d faces unmeshed (%s); points sampled on those faces stand in for (a) and they are not judged in (b)" % (
            len(occt.unmeshed), ", ".join(occt.describe_face(p, f) for p, f in occt.unmeshed[:3]))
    # (b) OCCT -> ours
    Pb, Tb = sample(Vt, Ft, max_samples, per_tri, rng)
    std = np.concatenate([i["standin"] for i in occt_fine]) if occt_fine else np.zeros(0, bool)
    if std.any():  # faces OCCT could not mesh are not judged in (b): its classifier may be off too
        keep = ~std[Tb]
        Pb, Tb = Pb[keep], Tb[keep]
    tgt_o = Target(Vo, Fo, T, rng)
    db, trib, nb = tgt_o.distance(Pb, T)
    k = int(np.argmax(db))
    res["samples_b"], res["exact_b"] = int(len(Pb)), int(nb)
    res["b_over_T"] = float(db[k] / T)
    tb = int(Tb[k])
    res["b_where"] = "%s at (%.4g, %.4g, %.4g), nearest ours %s" % (
        occt.describe_face(occt_fine[It[tb]]["proto"], int(Fat[tb])), *Pb[k], ours[Io[int(trib[k])]]["name"])
    res["b_exceed"] = int((db > BOUND * T).sum())
    if res["b_exceed"]:
        # an OCCT sample must lie on OCCT's B-rep (within T/10); one that does not is an OCCT
        # mesh artefact and does not count
        over = np.nonzero(db > BOUND * T)[0]
        chk = over[np.argsort(-db[over])[:VERIFY]]
        ex = verify_exact(occt, occt_fine, Pb, np.full(len(Pb), T), chk, 0.1 * T)
        bad = chk[ex > 0.5 * T]
        res["b_occt_artefacts"] = int(len(bad))
        db[bad] = 0.0
        # a sample off OCCT's B-rep by δ > T/10 (BRepMesh missed its deflection there) may lie
        # T + δ from ours without a fault of ours: judge it by that bound
        loose = chk[(ex > 0.1 * T) & (ex <= 0.5 * T)]
        lex = ex[(ex > 0.1 * T) & (ex <= 0.5 * T)]
        res["b_occt_loose"] = int(len(loose))
        db[loose] = np.where(db[loose] <= T + lex, np.minimum(db[loose], BOUND * T), db[loose])
        n, t = occt.excuse_tolerance(occt_fine, It[Tb], Pb, db, chk, T)
        res["b_exceed"] = int((db > BOUND * T).sum())
        k = int(np.argmax(db))
        res["b_over_T"] = float(db[k] / T)
        tb = int(Tb[k])
        res["b_where"] = "%s at (%.4g, %.4g, %.4g), nearest ours %s" % (
            occt.describe_face(occt_fine[It[tb]]["proto"], int(Fat[tb])), *Pb[k], ours[Io[int(trib[k])]]["name"])
        if n:
            res["b_tolerance"] = n
            res["b_where"] += " [%d samples within OCCT's own tolerance of an edge or vertex (up to %.3g mm), not counted]" % (n, t)
    # faces (OCCT) with most exceeding samples, for (b) — missing faces show up here
    if res["b_exceed"]:
        over = np.nonzero(db > BOUND * T)[0]
        keys = [(int(It[Tb[i]]), int(Fat[Tb[i]])) for i in over]
        uniq, cnt = np.unique(np.array(keys), axis=0, return_counts=True)
        order = np.argsort(-cnt)[:3]
        res["b_faces"] = ["%s (%d samples)" % (occt.describe_face(occt_fine[uniq[o][0]]["proto"], int(uniq[o][1])), cnt[o]) for o in order]
        res["fail"].append("b: %d OCCT samples farther than %.1f T from ours, worst %.2f T" % (res["b_exceed"], BOUND, res["b_over_T"]))
    if res["a_exceed"]:
        over = np.nonzero(da > BOUND * T)[0]
        keys = [(int(It[tria[i]]), int(Fat[tria[i]])) for i in over]
        uniq, cnt = np.unique(np.array(keys), axis=0, return_counts=True)
        order = np.argsort(-cnt)[:3]
        res["a_faces"] = ["%s (%d samples)" % (occt.describe_face(occt_fine[uniq[o][0]]["proto"], int(uniq[o][1])), cnt[o]) for o in order]
        res["fail"].insert(0, "a: %d of our samples farther than %.1f T from OCCT, worst %.2f T" % (res["a_exceed"], BOUND, res["a_over_T"]))
    return res


def read_built(brep, names):
    """The parts of a generated model as built (cad_generator.build_step's `built_brep`)."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepTools import BRepTools
    from OCP.TopoDS import TopoDS_Iterator, TopoDS_Shape

    c = TopoDS_Shape()
    if not BRepTools.Read_s(c, brep, BRep_Builder()):
        raise RuntimeError("could not read " + brep)
    parts, it = [], TopoDS_Iterator(c)
    while it.More():
        parts.append(it.Value())
        it.Next()
    if len(parts) != len(names):
        raise RuntimeError("%s holds %d parts, %d named" % (brep, len(parts), len(names)))
    return dict(zip(names, parts))


def max_tolerance(shape):
    """The largest tolerance OCCT gives a vertex, edge or face of `shape`: how far the B-rep
    may be from its own geometry (a boolean's vertex can carry millimetres)."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    worst = 0.0
    for kind, cast in ((TopAbs_VERTEX, TopoDS.Vertex), (TopAbs_EDGE, TopoDS.Edge), (TopAbs_FACE, TopoDS.Face)):
        e = TopExp_Explorer(shape, kind)
        while e.More():
            worst = max(worst, BRep_Tool.Tolerance_s(cast(e.Current())))
            e.Next()
    return worst


def built_beside(path, workdir):
    """A kept generated model's parts as OCCT built them: `X.brep.gz` beside `X.step[.gz]`,
    their names in `X.json` (`built.built_parts`). The shipped reduction is then judged as
    the generator judged it, not against OCCT's reading of its own STEP (gen-1-78: the read
    part is 75 mm² short of the part built, a hole where OCCT's reader dropped a face's corner
    at a vertex 20 off its circle). None when no such file is beside it."""
    stem = path[:-3] if path.endswith(".gz") else path
    stem = stem.rsplit(".", 1)[0]
    brep, recipe = stem + ".brep.gz", stem + ".json"
    if not (os.path.exists(brep) and os.path.exists(recipe)):
        return None
    names = json.load(open(recipe)).get("built", {}).get("built_parts")
    if not names:
        return None
    plain = os.path.join(workdir, os.path.basename(brep)[:-3])
    with gzip.open(brep, "rb") as fi, open(plain, "wb") as fo:
        shutil.copyfileobj(fi, fo)
    return read_built(plain, names)


def run_file(path, rels, pw, max_samples, workdir, seed, built=None):
    t0 = time.time()
    rows = []
    plain = path
    if path.endswith(".gz"):
        plain = os.path.join(workdir, os.path.basename(path)[:-3])
        with gzip.open(path, "rb") as fi, open(plain, "wb") as fo:
            shutil.copyfileobj(fi, fo)
    try:
        occt = OcctIges(plain) if is_iges(path) else Occt(plain, built)
    except Exception as e:  # noqa: BLE001
        return [{"file": path, "rel": r, "fail": ["OCCT: %s" % e], "time": time.time() - t0} for r in rels]
    lo, hi = occt.bbox()
    diag = float(np.linalg.norm(hi - lo))
    nfaces = sum(_count_faces(p["shape"]) for p in occt.protos)
    t_read = time.time() - t0
    for rel in rels:
        t1 = time.time()
        T = rel * diag
        rng = np.random.default_rng(seed)
        fine = occt.mesh(T / 10)
        glb = os.path.join(workdir, "ours.glb")
        # The model's own frame (STEP: z-up millimetres), not glTF's y-up metres: the judge
        # compares in OCCT's frame (`export`'s axis and unit change is tested in tests/cli_output.rs).
        r = patchwork_cmd(
            pw,
            ["export", "-o", glb, "--tolerance", repr(T), "--unit", "model", "--up", "model"],
            path,
            plain,
        )
        stats = our_stats(pw, path, plain, T)
        base = {"file": path, "faces": nfaces, "patches": stats.get("patches"), "diag": diag, "stats": stats}
        if r.returncode != 0:
            res = dict(base, rel=rel, T=T, fail=["patchwork export failed: " + (r.stderr.strip().splitlines() or ["?"])[-1]])
        else:
            ours = read_glb(glb)
            nt = sum(len(i["F"]) for i in ours)
            per_tri = 4 if nt < 20000 else (1 if nt < 200000 else 0)
            res = dict(base, **evaluate(occt, ours, rel, T, diag, fine, rng, max_samples, per_tri))
            if res["fail"] and getattr(occt, "roundtrip", None):
                res = judge_read_back(res, base, plain, ours, rel, T, diag, seed, max_samples, per_tri)
        res["placements_occt"] = occt.placements
        if getattr(occt, "roundtrip", None):
            res["roundtrip"] = occt.roundtrip
        res["time"] = time.time() - t1 + (t_read if rel == rels[0] else 0.0)
        rows.append(res)
    return rows


def judge_read_back(res, base, plain, ours, rel, T, diag, seed, max_samples, per_tri):
    """A generated model that fails against the parts OCCT built, where OCCT's reading of the
    STEP it wrote differs from them and is a valid shape (`BRepCheck_Analyzer`): judged again
    against that reading. The STEP is our only input, and what OCCT writes is not always what
    it built: seed 12 model 48, a fused cylinder built with 65 faces, was written with 58
    ADVANCED_FACEs (the 45 mm² torus face missing from the file was the judge's 4.5 T "nothing
    drawn there"); seed 14 model 37's sphere face, its parameter range 9.0 wide in u (more
    than its period), is read back with a cap the parts as built leave out (19.6 T on the
    reduced part), and BRepMesh leaves it unmeshed in the whole model. Passing against OCCT's
    own valid reading of the same file passes, and says so; failing both keeps the verdict
    against the parts as built. An invalid reading keeps it too: there the reader is the one
    that is wrong (seed 7 model 6: its sphere face read back with the hole covered twice
    fails BRepCheck), and a renderer wrong the same way must not pass by it."""
    from OCP.BRepCheck import BRepCheck_Analyzer

    try:
        occt = Occt(plain)
        valid = all(BRepCheck_Analyzer(p["shape"]).IsValid() for p in occt.protos)
    except Exception:  # noqa: BLE001 (the read-back cannot be judged: keep the verdict)
        return res
    if not valid:
        return res
    read_faces = sum(_count_faces(p["shape"]) for p in occt.protos)
    fine = occt.mesh(T / 10)
    alt = evaluate(occt, ours, rel, T, diag, fine, np.random.default_rng(seed), max_samples, per_tri)
    if alt["fail"]:
        return res
    why = "%d faces" % base["faces"]
    if res.get("occt_unmeshed_faces"):
        why += ", %d of them unmeshed by OCCT's BRepMesh" % res["occt_unmeshed_faces"]
    note = "fails against the parts as built (%s; a %.2f T, b %.2f T) but passes against OCCT's reading of the STEP it wrote (%d faces)" % (
        why, res.get("a_over_T", float("nan")), res.get("b_over_T", float("nan")), read_faces)
    alt = dict(base, **alt)
    alt["fail_note"] = "; ".join(n for n in (alt.get("fail_note"), note) if n)
    alt["judged_read_back"] = True
    return alt


# ----------------------------------------------------------------------------- table


def fmt_row(r):
    def g(k, f="%s"):
        v = r.get(k)
        return "-" if v is None else f % v

    return [os.path.basename(r["file"]), "%g" % r["rel"], g("T", "%.3g"), g("faces"), g("patches"),
            "%s/%s (%s)" % (g("inst_ours"), g("inst_occt"), g("placements_occt")), g("bbox_mismatch"),
            "%s/%s" % (g("samples_a"), g("samples_b")), g("a_over_T", "%.2f"), g("b_over_T", "%.2f"),
            stats_cell(r.get("stats")), g("time", "%.1f"), r.get("status", "?")]


def stats_cell(s):
    if s is None:
        return "-"
    if "error" in s:
        return "error"
    cell = "-" if s.get("ratio") is None else "%.2f" % s["ratio"]
    return cell + (" (%d skipped)" % s["skipped"] if s.get("skipped") else "")


HEAD = ["file", "rel", "T mm", "faces", "patches", "inst ours/occt (parts)", "bbox bad", "samples a/b", "a/T", "b/T", "stats e/eps", "s", "status"]


def print_table(rows):
    cells = [HEAD] + [fmt_row(r) for r in rows]
    w = [max(len(c[i]) for c in cells) for i in range(len(HEAD))]
    for k, c in enumerate(cells):
        log("  ".join(x.ljust(w[i]) for i, x in enumerate(c)))
        if k == 0:
            log("  ".join("-" * w[i] for i in range(len(HEAD))))
    for r in rows:
        if r.get("fail") or r.get("a_where"):
            log("%s @ rel %g:" % (os.path.basename(r["file"]), r["rel"]))
            if r.get("a_where"):
                log("    worst a: %.2f T  %s" % (r["a_over_T"], r["a_where"]))
                log("    worst b: %.2f T  %s" % (r["b_over_T"], r["b_where"]))
            if r.get("fail_note"):
                log("    note: " + r["fail_note"])
            for n in r.get("roundtrip", []):
                how = "judged as read back" if r.get("judged_read_back") else "judged as built"
                log("    %s; OCCT's reading of its STEP differs: %s" % (how, n))
            for f in r.get("fail", []):
                log("    FAIL " + f)
            for f in r.get("a_faces", []):
                log("      a over at: " + f)
            for f in r.get("b_faces", []):
                log("      b over at: " + f)


def load_known(path):
    known = {}
    if path and os.path.exists(path):
        for line in open(path):
            line = line.strip()
            if line and not line.startswith("#") and ":" in line:
                k, v = line.split(":", 1)
                known[k.strip()] = v.strip()
    return known


def default_files():
    fs = []
    for pat in ("models/*.stp", "models/*.step", "models/generated/*.step", "models/generated/*.step.gz", "models/corpus/*.stp", "models/corpus/*.step",
                "models/corpus/*.stp.gz", "models/corpus/*.step.gz", "models/*.igs", "models/*.iges",
                "models/corpus/*.igs", "models/corpus/*.iges", "models/corpus/*.igs.gz",
                "models/corpus/*.iges.gz"):
        fs += glob.glob(os.path.join(REPO, pat))
    return sorted(fs, key=lambda p: os.path.getsize(p))


# ----------------------------------------------------------------------------- self-test


def self_test(args):
    """Mutations the judge must catch. 'Ours' is OCCT's own mesh at deflection T written as a
    GLB in metres, y-up, under a transformed root node (so the GLB reader is exercised too)."""
    path = args.files[0] if args.files else os.path.join(REPO, "models", "as1-oc-214.stp")
    rel = 3e-3
    occt = Occt(path)
    lo, hi = occt.bbox()
    diag = float(np.linalg.norm(hi - lo))
    T = rel * diag
    coarse = occt.mesh(T)
    coarse = [dict(i, name="%s %d" % (i["name"], k)) for k, i in enumerate(coarse)]
    fine = occt.mesh(T / 10)
    work = tempfile.mkdtemp(prefix="occt_selftest_")
    # root transform: a rotation about z and a translation, in the y-up metre frame
    th = 0.7
    R = np.eye(4)
    R[:2, :2] = [[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]]
    R[:3, 3] = [0.1, -0.2, 0.05]
    to_frame = np.linalg.inv(Y_TO_Z @ np.diag([1000.0, 1000, 1000, 1]))  # z-up mm -> y-up m

    def roundtrip(inst):
        """Write `inst` (z-up mm world) as y-up metres under root R; read back."""
        local = [dict(i, V=i["V"] @ to_frame[:3, :3].T + to_frame[:3, 3]) for i in inst]
        g = os.path.join(work, "t.glb")
        write_glb(g, local, asset_extras={"unit": "m", "up": "y"}, parent_matrix=R)
        return read_glb(g)

    def check(name, inst, expect, forbid=()):
        rng = np.random.default_rng(1)
        ours = roundtrip(inst)
        r = evaluate(occt, ours, rel, T, diag, fine, rng, args.max_samples, 4)
        kinds = sorted({f.split(":")[0] for f in r["fail"]})
        ok = bool(set(expect) <= set(kinds) and not (set(forbid) & set(kinds)) and (expect or not kinds))
        log("  %-42s a/T %.2f  b/T %.2f  inst %d/%d  failures %s  must %s  must not %s  %s" % (
            name, r.get("a_over_T", np.nan), r.get("b_over_T", np.nan), r["inst_ours"], r["inst_occt"],
            kinds or "none", expect or "none", list(forbid) or "-", "ok" if ok else "WRONG"))
        for f in r["fail"]:
            log("      " + f)
        return ok

    log("self-test on %s, T = %.4g mm" % (os.path.basename(path), T))
    results = [check("unmutated (OCCT mesh at T)", coarse, [])]
    # (1) drop one instance
    results.append(check("drop one instance", coarse[:-1], ["c"], ["a"]))
    # biggest face over all instances by area
    best = None
    for k, ins in enumerate(coarse):
        V, F = ins["V"], ins["F"]
        ar = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
        for fid in np.unique(ins["face"]):
            a = ar[ins["face"] == fid].sum()
            if best is None or a > best[0]:
                best = (a, k, fid)
    _, k, fid = best
    # (2) remove 5 % of the triangles of the biggest face: a contiguous patch around a seed
    ins = coarse[k]
    idx = np.nonzero(ins["face"] == fid)[0]
    V, F = ins["V"], ins["F"]
    cen = V[F[idx]].mean(1)
    seed = cen[len(cen) // 2]
    n = max(1, int(round(0.05 * len(idx))))
    drop = idx[np.argsort(np.linalg.norm(cen - seed, axis=1))[:n]]
    keep = np.setdiff1d(np.arange(len(F)), drop)
    mut = list(coarse)
    mut[k] = dict(ins, F=F[keep], face=ins["face"][keep])
    results.append(check("remove 5%% of the biggest face (%d tris)" % n, mut, ["b"], ["a", "c"]))
    # (3) displace one face's vertices by 3T along its mean normal
    ins = coarse[k]
    V, F = ins["V"].copy(), ins["F"]
    sel = F[ins["face"] == fid]
    nrm = np.cross(V[sel[:, 1]] - V[sel[:, 0]], V[sel[:, 2]] - V[sel[:, 0]]).sum(0)
    nrm /= np.linalg.norm(nrm)
    V0 = V.copy()
    V[np.unique(sel)] += 3 * T * nrm
    mut = list(coarse)
    mut[k] = dict(ins, V=V)
    displaced = mut
    results.append(check("displace the biggest face by 3T", mut, ["a"]))
    # (4) a small dent, each way: 5 % of the biggest face moved by 3T. One of the two moves into
    # the solid, where the distance to the solid (not to its faces) is 0, and the exact check of
    # the exceeding samples (all of them: the dent is small) would have excused them (it did).
    out = np.dot(nrm, V0[sel].reshape(-1, 3).mean(0) - V0.mean(0)) > 0  # the part's centre behind the face
    for sign, way in ((1, "out of"), (-1, "into")) if out else ((-1, "out of"), (1, "into")):
        V = V0.copy()
        V[np.unique(F[drop])] += sign * 3 * T * nrm
        mut = list(coarse)
        mut[k] = dict(ins, V=V)
        results.append(check("move 5%% of the biggest face 3T %s the solid" % way, mut, ["a"]))
    # (5) the biggest face grown past its border in its own plane (or tangent plane): a sliver
    # 3T wide on its longest border edge. The exact check's fallback to the face's surface
    # (_surface_distance) must not take the surface past the face's border for the face.
    Fk = F[ins["face"] == fid]
    edges = np.sort(np.concatenate([Fk[:, [0, 1]], Fk[:, [1, 2]], Fk[:, [2, 0]]]), axis=1)
    uniq, cnt = np.unique(edges, axis=0, return_counts=True)
    border = uniq[cnt == 1]
    if len(border):
        i0, i1 = border[np.argmax(np.linalg.norm(V0[border[:, 1]] - V0[border[:, 0]], axis=1))]
        tri = Fk[np.nonzero(((Fk == i0) | (Fk == i1)).sum(1) == 2)[0][0]]
        inner = V0[[x for x in tri if x not in (i0, i1)][0]]
        a, b = V0[i0], V0[i1]
        along = (b - a) / np.linalg.norm(b - a)
        outward = (a - inner) - np.dot(a - inner, along) * along
        outward /= np.linalg.norm(outward)
        apex = 0.5 * (a + b) + 3 * T * outward
        Vg = np.vstack([V0, apex[None]])
        mut = list(coarse)
        mut[k] = dict(ins, V=Vg, F=np.vstack([F, [[i0, i1, len(V0)]]]), face=np.append(ins["face"], fid))
        results.append(check("grow the biggest face 3T past its border", mut, ["a"]))
    else:
        log("  grow the biggest face 3T past its border: FAILED (the face has no border edge)")
        results.append(False)
    # (6) OCCT's tolerance excuses a sample only in the tube of the tolerant edge
    # (`within_tolerance`): the edge of OCCT's part nearest the biggest face's
    # longest border edge is given a tolerance of 10T, and of the samples of the face displaced
    # by 3T, some are excused, but not most: the face is larger than the tube. (Two
    # evaluations at 20 000 samples: each costs CI time.)
    if len(border):
        from OCP.BRepExtrema import BRepExtrema_DistShapeShape
        from OCP.TopAbs import TopAbs_EDGE
        from OCP.TopExp import TopExp_Explorer

        _, v = Occt._in_part(ins, 0.5 * (a + b))
        e, edge = TopExp_Explorer(occt.protos[ins["proto"]]["subs"][ins["sub"]], TopAbs_EDGE), None
        while e.More():
            x = BRepExtrema_DistShapeShape(v, e.Current()).Value()
            if edge is None or x < edge[0]:
                edge = (x, e.Current())
            e.Next()
        ours = roundtrip(displaced)  # case (3)'s mutation

        def exceeding(tol):
            occt.__dict__["_tolerant"] = {(ins["proto"], ins["sub"]): [(tol, edge[1])] if tol else []}
            r = evaluate(occt, ours, rel, T, diag, fine, np.random.default_rng(1), min(args.max_samples, 20000), 4)
            return r.get("a_exceed", 0)

        n0, tube = exceeding(0.0), exceeding(10 * T)
        occt.__dict__.pop("_tolerant")
        # Excused in a 10T tube: some, at most the part of the face within 10T of the edge.
        ok6 = n0 / 2 < tube < n0
        log("  displace the biggest face 3T, an edge of OCCT's given a tolerance: samples over 1.1 T %d, with a tube "
            "10T wide %d (must be fewer, but over half)  %s" % (n0, tube, "ok" if ok6 else "WRONG"))
        results.append(ok6)
    # A generated model is judged as built: the round trip that changes seed 7 model 6's
    # sphere face (its hole covered twice when read back, part 1) must be seen.
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import cad_generator as gen

    step = os.path.join(work, "gen-7-6.step")
    try:
        info = build_isolated(gen, gen.recipe(7, 6), step)
        seen = Occt(step, read_built(step + ".brep", info["built_parts"])).roundtrip
        # Part 1 must be seen (OCCT does not build every part identically on every run, so
        # other parts are not required to match).
        ok_rt = any(x.startswith("part 1:") for x in seen)
        log("  a generated model judged as built: round-trip differences %s  %s" % (seen or "none", "ok" if ok_rt else "FAILED (expected part 1)"))
        # Its read-back is not a valid shape (the reader covers the hole twice): a failure
        # against the parts is not judged again against that reading.
        failing = {"fail": ["(self-test)"]}
        kept = judge_read_back(failing, {"faces": 0}, step, None, 1e-3, 1.0, 1.0, 0, 100, 1) is failing
        log("  a reader's error is not judged by: %s" % ("ok" if kept else "FAILED (judged against the read-back)"))
        ok_rt = ok_rt and kept
    except Exception as e:  # noqa: BLE001
        ok_rt = False
        log("  a generated model judged as built: FAILED (%s)" % e)
    results.append(ok_rt)
    shutil.rmtree(work, ignore_errors=True)
    ok = all(results)
    log("self-test: %d passed, %d failed" % (sum(results), len(results) - sum(results)))
    return 0 if ok else 1


# ----------------------------------------------------------------------------- generated models


def build_isolated(gen, rec, step):
    """gen.build_step in a forked child: OCCT can crash on a recipe (seed 1 model 109: a
    segmentation fault), which must cost that model only, not the run. A crash is
    gen.Dropped."""
    import multiprocessing as mp
    import pickle

    out = step + ".result"

    def child():
        try:
            r = ("ok", gen.build_step(rec, step, step + ".brep"))
        except gen.Dropped as e:
            r = ("dropped", str(e))
        except BaseException as e:  # noqa: BLE001 - reported to the parent as it is
            r = ("error", "%s: %s" % (type(e).__name__, e))
        with open(out, "wb") as fh:
            pickle.dump(r, fh)

    if os.path.exists(out):
        os.remove(out)
    p = mp.get_context("fork").Process(target=child)
    p.start()
    p.join()
    if not os.path.exists(out):
        raise gen.Dropped("OCCT crashed building it (exit code %s)" % p.exitcode)
    with open(out, "rb") as fh:
        kind, value = pickle.load(fh)
    os.remove(out)
    if kind == "ok":
        return value
    if kind == "dropped":
        raise gen.Dropped(value)
    raise RuntimeError("building the model failed: " + value)


def keep_generated(step, keep, name, rec, info, why):
    """Copies a generated model that failed or on which `stats` disagreed with the judge, as
    OCCT built it this time, to KEEP: its STEP and its parts (gzipped) and its recipe with the
    names of the parts built (`.json`, what `built_beside` reads), so that the corpus run
    judges it as built. OCCT does not build every recipe identically run to run (gen-1-78's
    stats-only disagreement came back in 1 of 6 builds), so the input is kept while it exists."""
    os.makedirs(keep, exist_ok=True)
    for src, dst in ((step, name + ".step.gz"), (step + ".brep", name + ".brep.gz")):
        if os.path.exists(src):
            with open(src, "rb") as fi, gzip.open(os.path.join(keep, dst), "wb") as fo:
                shutil.copyfileobj(fi, fo)
    with open(os.path.join(keep, name + ".json"), "w") as fh:
        json.dump(dict(rec, built={k: v for k, v in info.items() if k != "kept"}, failure=why), fh, indent=1)
    log("    kept as built this time: %s" % os.path.join(keep, name + ".step.gz"))


def judge_generated(args):
    """Build models of the seeded generator and judge each like a file; a failing model is
    reduced (cad_generator.reduce_recipe) when --reduce-to is given. Exit 1 on any failure."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import cad_generator as gen

    rels = [float(x) for x in args.rel.split(",")]
    known = load_known(args.known_failures)
    work = tempfile.mkdtemp(prefix="occt_generated_")
    t0 = time.time()
    rows, failed, knownfail, notbuilt, seen = [], [], [], [], {}

    def judge(rec, name):
        step = os.path.join(work, name + ".step")
        info = build_isolated(gen, rec, step)
        try:
            built = read_built(step + ".brep", info["built_parts"])
        except Exception as e:  # noqa: BLE001 - judged against OCCT's reading, saying so
            log("    %s: the parts as built could not be read (%s): judged against OCCT's reading of its STEP" % (name, e))
            built = None
        res = run_file(step, rels, args.patchwork, args.max_samples, work, args.seed, built)
        # A part whose B-rep OCCT only holds together with a tolerance beyond T (seed 29 model
        # 25: a box in common with a sphere and a cylinder, less a cone; a vertex of 9.17 mm,
        # edges 5 mm off their faces, read back otherwise than built) is defined only to that
        # tolerance: a mesh that agrees with OCCT's within T passes, but one that does not is
        # no evidence of a fault, and the model is set aside (seed 1 model 32, 0.6 mm at T
        # 0.477, passes and is judged).
        Ts = [r["T"] for r in res if r.get("T")]
        if built and Ts and any(r["fail"] for r in res):
            tol = max(max_tolerance(s) for s in built.values())
            if tol > min(Ts):
                raise gen.Dropped("it fails, but OCCT's parts as built carry a tolerance of %.3g mm, beyond T %.3g mm" % (
                    tol, min(Ts)))
        return info, res

    try:
        for i in range(args.gen_start, args.gen_start + args.generate):
            rec = gen.recipe(args.gen_seed, i)
            name = "gen-%d-%d" % (args.gen_seed, i)
            t1 = time.time()
            try:
                info, res = judge(rec, name)
            except gen.Dropped as e:
                notbuilt.append(name)
                log("... %s: not built (%s)" % (name, e))
                continue
            fs = gen.features(rec, info)
            for f in fs:
                seen[f] = seen.get(f, 0) + 1
            bad = [r for r in res if r["fail"]]
            listed = name + ".step" in known
            why = [f for r in res for f in r["fail"]] + [
                "stats only: error/eps %.3f (%s)" % (r["stats"].get("ratio") or 0.0, r["stats"].get("worst_face"))
                for r in res if r.get("stats") is not None and stats_bad(r) and not judge_bad(r)] + [
                "judge only" for r in res if r.get("stats") is not None and judge_bad(r) and not stats_bad(r)]
            if args.keep and why:
                keep_generated(os.path.join(work, name + ".step"), args.keep, name, rec, info, why)
            for r in res:
                r["file"] = name + ".step"
                r["features"] = fs
                r["status"] = ("KNOWN" if listed else "FAIL") if r["fail"] else ("FIXED (remove from list)" if listed else "pass")
                rows.append(r)
            log("... %s (%d placed faces; %s): %s (%.1f s)" % (name, info["faces"], " ".join(fs),
                                                             "; ".join(bad[0]["fail"]) if bad else "pass", time.time() - t1))
            if bad and listed:
                knownfail.append(name)
            elif bad:
                failed.append(name)
                if args.reduce_to:
                    def fails(r2):
                        try:
                            _, rr = judge(r2, name + "-try")
                        except gen.Dropped:
                            return False
                        return any(x["fail"] for x in rr)

                    small = gen.reduce_recipe(rec, fails, log=log)
                    os.makedirs(args.reduce_to, exist_ok=True)
                    out = os.path.join(args.reduce_to, name + ".step")
                    info2 = gen.build_step(small, out, out[:-5] + ".brep")
                    with open(out[:-5] + ".brep", "rb") as fi, gzip.open(out[:-5] + ".brep.gz", "wb") as fo:
                        shutil.copyfileobj(fi, fo)
                    os.remove(out[:-5] + ".brep")
                    with open(out[:-5] + ".json", "w") as fh:
                        json.dump(dict(small, built={k: v for k, v in info2.items() if k != "kept"},
                                       failure=bad[0]["fail"]), fh, indent=1)
                    log("    reduced to %d parts, %d placed, %d faces: kept as %s" % (
                        info2["parts"], info2["leaves"], info2["faces"], os.path.relpath(out, REPO)))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    total = time.time() - t0
    log("")
    print_table(rows)
    log("")
    disagree = print_agreement(rows, known)
    log("features judged: %s" % ", ".join("%s %d" % (f, seen.get(f, 0)) for f in gen.FEATURES))
    n = args.generate - len(notbuilt)
    log("occt_fidelity --generate: %d models of seed %d from %d (%d built, %d not built) x %d tolerances in %.1f s: "
        "%d failed%s, %d known failures%s" % (
            args.generate, args.gen_seed, args.gen_start, n, len(notbuilt), len(rels), total, len(failed),
            (" (" + " ".join(failed) + ")") if failed else "", len(knownfail),
            (" (" + " ".join(knownfail) + ")") if knownfail else ""))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"total_s": total, "rows": rows, "not_built": notbuilt, "disagreements": disagree}, fh, indent=1,
                      default=float)
    if args.require_agreement and disagree:
        log("occt_fidelity: %d disagreements of `stats` with the judge (--require-agreement)" % disagree)
        return 1
    return 1 if failed else 0


# ----------------------------------------------------------------------------- main


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*", help="STEP (.stp/.step) or IGES (.igs/.iges) files, optionally .gz; default: the corpus")
    ap.add_argument("--rel", default="3e-3", help="relative tolerance(s), comma-separated (T = rel x bbox diagonal)")
    ap.add_argument("--patchwork", default=os.environ.get("PATCHWORK", os.path.join(REPO, "target", "release", "patchwork")))
    ap.add_argument("--json", help="write the table as JSON here")
    ap.add_argument("--known-failures", help="file of `file: reason` lines")
    ap.add_argument("--max-samples", type=int, default=60000, help="cap on samples per direction and file")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--self-test", action="store_true", help="check that the judge catches mutated exports")
    ap.add_argument("--generate", type=int, metavar="N",
                    help="judge N models of tools/cad_generator.py (sequence --gen-seed, from --gen-start) instead of files")
    ap.add_argument("--gen-seed", type=int, default=1, help="the generator's sequence (default 1)")
    ap.add_argument("--gen-start", type=int, default=0, help="first model index of the sequence")
    ap.add_argument("--reduce-to", metavar="DIR",
                    help="with --generate: reduce each failing model to the smallest recipe that still fails and keep "
                         "it in DIR as gen-SEED-INDEX.step with its recipe (.json)")
    ap.add_argument("--keep", metavar="DIR",
                    help="with --generate: copy every model that fails or on which stats disagrees with the judge, "
                         "as OCCT built it this time (STEP and parts, gzipped), to DIR")
    ap.add_argument("--require-agreement", action="store_true",
                    help="exit 1 when `stats --tolerance T` disagrees with the judge on a file not listed in "
                         "--known-failures (its trimmed error/eps above 1.1, or a skipped face, exactly when the "
                         "judge finds samples beyond 1.1 T)")
    args = ap.parse_args()
    if args.self_test:
        return self_test(args)
    if args.generate:
        return judge_generated(args)
    rels = [float(x) for x in args.rel.split(",")]
    files = args.files or default_files()
    known = load_known(args.known_failures)
    t0 = time.time()
    rows = []
    work = tempfile.mkdtemp(prefix="occt_fidelity_")
    try:
        for f in files:
            log("... %s" % os.path.relpath(f, REPO) if f.startswith(REPO) else f)
            built = built_beside(os.path.abspath(f), work)
            if built is not None:
                log("    judged as built: the parts OCCT built are beside it (.brep.gz)")
            for r in run_file(os.path.abspath(f), rels, args.patchwork, args.max_samples, work, args.seed, built):
                rows.append(r)
                log("    rel %g: %s (%.1f s)" % (r["rel"], "; ".join(r["fail"]) or "pass", r["time"]))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    unexpected = 0
    fixed = 0
    for r in rows:
        base = os.path.basename(r["file"])
        listed = base in known or os.path.relpath(r["file"], REPO) in known
        if r["fail"]:
            r["status"] = "KNOWN" if listed else "FAIL"
            unexpected += 0 if listed else 1
        else:
            r["status"] = "FIXED (remove from list)" if listed else "pass"
            fixed += 1 if listed else 0
    total = time.time() - t0
    log("")
    print_table(rows)
    npass = sum(1 for r in rows if not r["fail"])
    log("")
    disagree = print_agreement(rows, known)
    nknown = sum(1 for r in rows if r["status"] == "KNOWN")
    log("occt_fidelity: %d files x %d tolerances in %.1f s: %d pass, %d known failures (KNOWN), %d unexpected failures, %d fixed" % (
        len(files), len(rels), total, npass, nknown, unexpected, fixed))
    log("(known failures are counted as skipped below; the table above shows them as they are)")
    log("fidelity: %d passed, %d failed, %d skipped" % (npass, unexpected, nknown))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"total_s": total, "rows": rows, "disagreements": disagree}, fh, indent=1, default=float)
    if args.require_agreement and disagree:
        log("occt_fidelity: %d disagreements of `stats` with the judge (--require-agreement)" % disagree)
        return 1
    return 1 if unexpected else 0


if __name__ == "__main__":
    sys.exit(main())
