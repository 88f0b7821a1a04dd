#!/usr/bin/env python3
"""Seeded generator of CAD models for the Open CASCADE judge (issue 29, item 2).

`recipe(seed, index)` draws a model description — plain JSON, so that a failing model can be
written down, reduced and rebuilt — and `build_step(recipe, path)` builds it with Open CASCADE
(OCP) and writes it as STEP. The same (seed, index) gives the same recipe and the same file on
every machine with the pinned OCP.

A recipe is an assembly tree of parts:

  {"seed", "index", "unit": "mm"|"inch"|"m", "schema": "AP203"|"AP214"|"AP242",
   "parts": [part, ...],
   "tree": node}  node = {"name", "loc": [rx, ry, rz (deg), tx, ty, tz],
                          "children": [node...]} | {"name", "part": i, "loc": ...}

A part is a base body and a list of operations:

  base: box, cylinder, cone (wide ones too), sphere, torus, wedge, loft through closed
        B-spline sections, revolved B-spline profile (full or partial turn), extruded
        closed B-spline profile, spring (circle swept along a helix), threaded bolt
        (V-profile swept along a helix and fused to its core), text (font glyphs extruded;
        skipped with a note when no font is installed)
  ops:  fuse / cut / common with a placed primitive, constant fillet, variable fillet,
        chamfer, shell (hollowed, one face removed), offset (grown solid), draft (side faces
        of a planar-sided body tilted)

Parts are referenced by several leaves of the tree (repeated parts, linear and circular
patterns), sub-assemblies nest with rotations. An operation OCCT cannot perform on the body at
hand (a fillet too large, a boolean that fails) is dropped and recorded in the model's
`dropped` list; the model is always a valid, non-empty shape that OCCT's checker accepts.

Reduction (`reduce_recipe`) removes tree nodes, parts' operations and finally simplifies units
and schema, keeping each step that still fails a predicate: a failing generated model is kept
as the smallest recipe (and STEP file) that still fails.

Command line: `cad_generator.py --seed S --count N --out DIR` writes DIR/gen-S-I.step and
DIR/gen-S-I.json; `--describe` prints each recipe's features.
"""

import argparse
import copy
import json
import math
import os
import random
import sys

FEATURES = [
    "box", "cylinder", "cone", "wide_cone", "sphere", "torus", "wedge", "loft", "revolve",
    "extrude_spline", "spring", "thread", "text",
    "fuse", "cut", "common", "fillet", "variable_fillet", "chamfer", "shell", "offset", "draft",
    "repeat", "linear_pattern", "circular_pattern", "nested", "rotated",
    "unit_inch", "unit_m", "ap203", "ap214", "ap242",
]

BASES = ["box", "cylinder", "cone", "wide_cone", "sphere", "torus", "wedge", "loft", "revolve",
         "extrude_spline", "spring", "thread", "text"]
OPS = ["fuse", "cut", "common", "fillet", "variable_fillet", "chamfer", "shell", "offset", "draft"]
PRIMS = ["box", "cylinder", "cone", "sphere", "torus"]


# ----------------------------------------------------------------------------- recipes


def _r(rng, lo, hi, nd=3):
    return round(rng.uniform(lo, hi), nd)


def _base(rng, kind):
    """Parameters of a base body, about 10..60 mm in size."""
    if kind == "box":
        return {"kind": kind, "d": [_r(rng, 10, 60), _r(rng, 10, 60), _r(rng, 5, 40)]}
    if kind == "cylinder":
        return {"kind": kind, "r": _r(rng, 4, 25), "h": _r(rng, 5, 60), "angle": rng.choice([360, 360, 360, _r(rng, 60, 300)])}
    if kind == "cone":
        return {"kind": kind, "r1": _r(rng, 5, 25), "r2": _r(rng, 0, 15), "h": _r(rng, 5, 50)}
    if kind == "wide_cone":  # half-angle near 90 degrees: the cones trj4 got wrong
        r1 = _r(rng, 20, 50)
        return {"kind": kind, "r1": r1, "r2": round(r1 * rng.uniform(0.0, 0.3), 3), "h": _r(rng, 0.8, 5)}
    if kind == "sphere":
        return {"kind": kind, "r": _r(rng, 5, 30), "a1": rng.choice([-90, -90, _r(rng, -80, 0)]),
                "a2": rng.choice([90, 90, _r(rng, 10, 80)]), "a3": rng.choice([360, 360, _r(rng, 90, 300)])}
    if kind == "torus":
        R = _r(rng, 10, 30)
        return {"kind": kind, "R": R, "r": round(R * rng.uniform(0.1, 0.6), 3), "angle": rng.choice([360, 360, _r(rng, 60, 300)])}
    if kind == "wedge":
        dx, dy, dz = _r(rng, 10, 50), _r(rng, 10, 50), _r(rng, 10, 50)
        return {"kind": kind, "d": [dx, dy, dz], "ltx": round(dx * rng.uniform(0.0, 0.9), 3)}
    if kind == "loft":
        n = rng.randint(2, 4)
        secs, z = [], 0.0
        for _ in range(n):
            m = rng.randint(4, 7)
            rad = _r(rng, 6, 20)
            secs.append({"z": round(z, 3), "r": [round(rad * rng.uniform(0.7, 1.3), 3) for _ in range(m)],
                         "dx": _r(rng, -4, 4), "dy": _r(rng, -4, 4)})
            z += rng.uniform(8, 25)
        return {"kind": kind, "sections": secs, "ruled": rng.random() < 0.25}
    if kind == "revolve":
        m = rng.randint(3, 6)
        h = _r(rng, 20, 60)
        return {"kind": kind, "h": h, "r": [_r(rng, 4, 20) for _ in range(m)],
                "angle": rng.choice([360, 360, _r(rng, 90, 300)])}
    if kind == "extrude_spline":
        m = rng.randint(4, 8)
        return {"kind": kind, "r": [_r(rng, 8, 25) for _ in range(m)], "h": _r(rng, 3, 30),
                "taper": rng.random() < 0.3}
    if kind == "spring":
        R = _r(rng, 6, 20)
        return {"kind": kind, "R": R, "wire": round(R * rng.uniform(0.08, 0.2), 3),
                "pitch": round(R * rng.uniform(0.6, 1.2), 3), "turns": _r(rng, 1.5, 4, 2)}
    if kind == "thread":
        R = _r(rng, 3, 10)
        # Up to 16 turns (5 until 2026-12-06): an edge of 8 turns or more, one B-spline, is
        # where the tessellator's edge sampling aliased (gen-7-13-8turns).
        return {"kind": kind, "R": R, "pitch": round(R * rng.uniform(0.25, 0.5), 3), "turns": _r(rng, 2, 16, 2),
                "head": rng.random() < 0.6}
    if kind == "text":
        return {"kind": kind, "text": rng.choice(["CAD", "Patch", "a8Q", "OCCT", "R2-D2", "&%"]),
                "size": _r(rng, 8, 20), "h": _r(rng, 1, 6)}
    raise ValueError(kind)


def _prim(rng, kind):
    p = _base(rng, kind)
    p["loc"] = [_r(rng, 0, 360, 1), _r(rng, 0, 360, 1), _r(rng, 0, 360, 1), _r(rng, -0.5, 0.5), _r(rng, -0.5, 0.5), _r(rng, -0.5, 0.5)]
    return p


def _op(rng, kind):
    if kind in ("fuse", "cut", "common"):
        return {"op": kind, "tool": _prim(rng, rng.choice(PRIMS))}
    if kind == "fillet":
        return {"op": kind, "r": _r(rng, 0.3, 4), "edges": rng.randint(1, 6), "pick": rng.randint(0, 10 ** 6)}
    if kind == "variable_fillet":
        return {"op": kind, "r1": _r(rng, 0.3, 3), "r2": _r(rng, 0.5, 5), "edges": rng.randint(1, 3), "pick": rng.randint(0, 10 ** 6)}
    if kind == "chamfer":
        return {"op": kind, "d": _r(rng, 0.3, 3), "edges": rng.randint(1, 6), "pick": rng.randint(0, 10 ** 6)}
    if kind == "shell":
        return {"op": kind, "t": _r(rng, -2.5, -0.5), "pick": rng.randint(0, 10 ** 6)}
    if kind == "offset":
        return {"op": kind, "d": _r(rng, 0.3, 3)}
    if kind == "draft":
        return {"op": kind, "deg": _r(rng, 1, 12, 2), "dir": rng.choice([[0, 0, 1], [0, 1, 0], [1, 0, 0]])}
    raise ValueError(kind)


def recipe(seed, index):
    """The model `index` of the sequence `seed`: a JSON-able dict (see the module's doc)."""
    rng = random.Random("patchwork-cad-generator:%d:%d" % (seed, index))
    unit = rng.choices(["mm", "inch", "m"], weights=[6, 2, 2])[0]
    schema = rng.choice(["AP203", "AP214", "AP242"])
    nparts = rng.choices([1, 2, 3, 4], weights=[4, 3, 2, 1])[0]
    parts = []
    for _ in range(nparts):
        base = _base(rng, rng.choice(BASES))
        nops = rng.choices([0, 1, 2, 3], weights=[2, 4, 3, 1])[0]
        ops = [_op(rng, rng.choice(OPS)) for _ in range(nops)]
        parts.append({"base": base, "ops": ops})
    # assembly tree: each part placed once or in a pattern, some inside a rotated sub-assembly
    leaves = []
    for i in range(nparts):
        shape = rng.choices(["once", "repeat", "linear", "circular"], weights=[5, 2, 2, 2])[0]
        if shape == "once":
            leaves.append({"name": "part %d" % i, "part": i, "loc": _loc(rng, 80)})
        elif shape == "repeat":
            for k in range(rng.randint(2, 3)):
                leaves.append({"name": "part %d copy %d" % (i, k), "part": i, "loc": _loc(rng, 120), "pattern": "repeat"})
        elif shape == "linear":
            n, step = rng.randint(2, 5), _r(rng, 70, 120)
            leaves.append({"name": "part %d row" % i, "loc": _loc(rng, 60), "pattern": "linear_pattern", "children": [
                {"name": "part %d #%d" % (i, k), "part": i, "loc": [0, 0, 0, k * step, 0, 0]} for k in range(n)]})
        else:
            n, rad = rng.randint(3, 6), _r(rng, 80, 150)
            leaves.append({"name": "part %d ring" % i, "loc": _loc(rng, 60), "pattern": "circular_pattern", "children": [
                {"name": "part %d @%d" % (i, k), "part": i,
                 "loc": [0, 0, round(360.0 * k / n, 3), round(rad * math.cos(2 * math.pi * k / n), 3),
                         round(rad * math.sin(2 * math.pi * k / n), 3), 0]} for k in range(n)]})
    if len(leaves) > 1 and rng.random() < 0.5:
        k = rng.randint(1, len(leaves) - 1)
        sub = {"name": "sub-assembly", "loc": _loc(rng, 100, rotate=True), "children": leaves[k:], "pattern": "nested"}
        leaves = leaves[:k] + [sub]
    tree = {"name": "model %d-%d" % (seed, index), "loc": [0, 0, 0, 0, 0, 0], "children": leaves}
    return {"seed": seed, "index": index, "unit": unit, "schema": schema, "parts": parts, "tree": tree}


def _loc(rng, spread, rotate=None):
    rot = rotate if rotate is not None else rng.random() < 0.6
    a = [_r(rng, -180, 180, 1) for _ in range(3)] if rot else [0, 0, 0]
    return a + [_r(rng, -spread, spread) for _ in range(3)]


def features(rec, built=None):
    """The generator features a recipe uses (names from FEATURES); given `build_step`'s
    result, only those of the parts and operations that were built."""
    fs = set()
    used = {n["part"] for n in _leaves(rec["tree"])}
    for i, p in enumerate(rec["parts"]):
        if i not in used or (built is not None and i not in built["kept"]):
            continue
        fs.add(p["base"]["kind"])
        for j, o in enumerate(p["ops"]):
            if built is None or j in built["kept"][i]:
                fs.add(o["op"])
    fs.add({"inch": "unit_inch", "m": "unit_m"}.get(rec["unit"], "unit_mm"))
    fs.add(rec["schema"].lower())

    def walk(n):
        if "pattern" in n:
            fs.add(n["pattern"])
        if any(abs(x) > 0 for x in n["loc"][:3]):
            fs.add("rotated")
        for c in n.get("children", []):
            walk(c)

    walk(rec["tree"])
    fs.discard("unit_mm")
    return sorted(fs)


# ----------------------------------------------------------------------------- reduction


def _variants(rec):
    """Smaller recipes than `rec`, most aggressive first."""
    # drop a whole subtree / leaf (keep at least one leaf)
    paths = []

    def walk(n, path):
        for k, c in enumerate(n.get("children", [])):
            paths.append(path + [k])
            walk(c, path + [k])

    walk(rec["tree"], [])
    for p in paths:
        r = copy.deepcopy(rec)
        n = r["tree"]
        for k in p[:-1]:
            n = n["children"][k]
        del n["children"][p[-1]]
        if _leaf_count(r["tree"]):
            yield "drop tree node %s" % p, r
    # flatten: a node with children replaced by its first child (placement composed away)
    for p in paths:
        r = copy.deepcopy(rec)
        n = r["tree"]
        for k in p[:-1]:
            n = n["children"][k]
        c = n["children"][p[-1]]
        if c.get("children"):
            n["children"][p[-1]] = dict(c["children"][0], loc=c["loc"])
            yield "flatten tree node %s" % p, r
    # drop operations
    for i, part in enumerate(rec["parts"]):
        for j in range(len(part["ops"])):
            r = copy.deepcopy(rec)
            del r["parts"][i]["ops"][j]
            yield "drop op %d of part %d" % (j, i), r
    # placements to identity
    def unplace(n):
        n["loc"] = [0, 0, 0, 0, 0, 0]
        for c in n.get("children", []):
            unplace(c)

    r = copy.deepcopy(rec)
    unplace(r["tree"])
    if r != rec:
        yield "identity placements", r
    if rec["unit"] != "mm":
        yield "unit mm", dict(copy.deepcopy(rec), unit="mm")
    if rec["schema"] != "AP214":
        yield "schema AP214", dict(copy.deepcopy(rec), schema="AP214")


def _leaf_count(n):
    return (1 if "part" in n else 0) + sum(_leaf_count(c) for c in n.get("children", []))


def reduce_recipe(rec, fails, log=print):
    """Greedy reduction: apply the first variant that still `fails(recipe)`, until none does."""
    cur = rec
    changed = True
    while changed:
        changed = False
        for what, v in _variants(cur):
            if fails(v):
                log("  reduce: %s -> still fails" % what)
                cur = v
                changed = True
                break
    return cur


# ----------------------------------------------------------------------------- building


def _trsf(loc):
    from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Trsf, gp_Vec

    t = gp_Trsf()
    for axis, deg in zip(((1, 0, 0), (0, 1, 0), (0, 0, 1)), loc[:3]):
        if deg:
            r = gp_Trsf()
            r.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(*axis)), math.radians(deg))
            t = r.Multiplied(t)
    m = gp_Trsf()
    m.SetTranslation(gp_Vec(*loc[3:6]))
    return m.Multiplied(t)


def _moved(shape, trsf):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform

    return BRepBuilderAPI_Transform(shape, trsf, True).Shape()


def _spline_closed(pts):
    """A periodic B-spline through points (gp_Pnt list)."""
    from OCP.GeomAPI import GeomAPI_Interpolate
    from OCP.OCP.collections import HArray1_gp_Pnt as TColgp_HArray1OfPnt

    arr = TColgp_HArray1OfPnt(1, len(pts))
    for k, p in enumerate(pts):
        arr.SetValue(k + 1, p)
    it = GeomAPI_Interpolate(arr, True, 1e-7)
    it.Perform()
    return it.Curve()


def _star(radii, z=0.0, dx=0.0, dy=0.0):
    from OCP.gp import gp_Pnt

    n = len(radii)
    return [gp_Pnt(dx + r * math.cos(2 * math.pi * k / n), dy + r * math.sin(2 * math.pi * k / n), z) for k, r in enumerate(radii)]


def _wire_of_curve(c):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeWire

    return BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(c).Edge()).Wire()


def _helix_edge(R, pitch, turns, z0=0.0):
    """A helix of radius R as a line on a cylinder's parameter plane (u = angle, v = height)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
    from OCP.BRepLib import BRepLib
    from OCP.Geom import Geom_CylindricalSurface
    from OCP.Geom2d import Geom2d_Line
    from OCP.gp import gp_Ax3, gp_Dir, gp_Dir2d, gp_Pnt, gp_Pnt2d

    surf = Geom_CylindricalSurface(gp_Ax3(gp_Pnt(0, 0, z0), gp_Dir(0, 0, 1)), R)
    d = gp_Dir2d(2 * math.pi, pitch)
    line = Geom2d_Line(gp_Pnt2d(0, 0), d)
    length = turns * math.hypot(2 * math.pi, pitch)
    e = BRepBuilderAPI_MakeEdge(line, surf, 0.0, length).Edge()
    BRepLib.BuildCurves3d_s(e)
    return e


def _sweep(profile_wire, spine_edge):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeWire
    from OCP.BRepOffsetAPI import BRepOffsetAPI_MakePipeShell
    from OCP.gp import gp_Dir

    spine = BRepBuilderAPI_MakeWire(spine_edge).Wire()
    ps = BRepOffsetAPI_MakePipeShell(spine)
    ps.SetMode(gp_Dir(0, 0, 1))  # binormal along the axis: the profile keeps its plane through the axis
    ps.Add(profile_wire)
    ps.Build()
    ps.MakeSolid()
    return ps.Shape()


def _polygon_wire(pts):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakePolygon

    poly = BRepBuilderAPI_MakePolygon()
    for p in pts:
        poly.Add(p)
    poly.Close()
    return poly.Wire()


class Dropped(Exception):
    pass


def _occt_errors():
    # OCP binds every OCCT exception straight to Python's Exception (not to Standard_Failure
    # as in C++), so each is named: an op that raises Standard_NoSuchObject
    # (MakeThickSolidByJoin: "no parameter on edge", seed 1 model 81) or StdFail_NotDone
    # (MakeThickSolidByJoin: "command not done", seed 16 model 10, which stopped the whole
    # run) is dropped like any other. The exception packages of the modelling algorithms.
    import importlib

    found = []
    for module in ("Standard", "StdFail", "gp", "Geom", "Geom2d", "TopoDS", "BRep", "BRepExtrema"):
        try:
            m = importlib.import_module("OCP." + module)
        except ImportError:
            continue
        for n in dir(m):
            c = getattr(m, n)
            if isinstance(c, type) and issubclass(c, BaseException) and "_" in n:
                found.append(c)
    return tuple(found) + (RuntimeError,)


OCCT_ERRORS = ()  # set in build_step (OCP is imported on first use)


def _font():
    for p in ("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf", "/usr/share/fonts/TTF/DejaVuSans.ttf",
              "/usr/share/fonts/dejavu/DejaVuSans.ttf"):
        if os.path.exists(p):
            return p
    return None


def build_base(b):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.BRepOffsetAPI import BRepOffsetAPI_ThruSections
    from OCP.BRepPrimAPI import (BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCone, BRepPrimAPI_MakeCylinder,
                                 BRepPrimAPI_MakePrism, BRepPrimAPI_MakeRevol, BRepPrimAPI_MakeSphere,
                                 BRepPrimAPI_MakeTorus, BRepPrimAPI_MakeWedge)
    from OCP.gp import gp_Ax1, gp_Ax2, gp_Dir, gp_Pnt, gp_Vec

    k = b["kind"]
    if k == "box":
        return BRepPrimAPI_MakeBox(*b["d"]).Shape()
    if k == "cylinder":
        return BRepPrimAPI_MakeCylinder(b["r"], b["h"], math.radians(b["angle"])).Shape()
    if k in ("cone", "wide_cone"):
        return BRepPrimAPI_MakeCone(b["r1"], b["r2"], b["h"]).Shape()
    if k == "sphere":
        return BRepPrimAPI_MakeSphere(b["r"], math.radians(b["a1"]), math.radians(b["a2"]), math.radians(b["a3"])).Shape()
    if k == "torus":
        return BRepPrimAPI_MakeTorus(b["R"], b["r"], math.radians(b["angle"])).Shape()
    if k == "wedge":
        return BRepPrimAPI_MakeWedge(*b["d"], b["ltx"]).Shape()
    if k == "loft":
        ts = BRepOffsetAPI_ThruSections(True, b["ruled"], 1e-6)
        for s in b["sections"]:
            ts.AddWire(_wire_of_curve(_spline_closed(_star(s["r"], s["z"], s["dx"], s["dy"]))))
        ts.Build()
        return ts.Shape()
    if k == "revolve":
        from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeWire
        from OCP.GeomAPI import GeomAPI_Interpolate
        from OCP.OCP.collections import HArray1_gp_Pnt as TColgp_HArray1OfPnt

        n = len(b["r"])
        pts = [gp_Pnt(r, 0, b["h"] * k2 / (n - 1)) for k2, r in enumerate(b["r"])]
        arr = TColgp_HArray1OfPnt(1, n)
        for i, p in enumerate(pts):
            arr.SetValue(i + 1, p)
        it = GeomAPI_Interpolate(arr, False, 1e-7)
        it.Perform()
        w = BRepBuilderAPI_MakeWire()
        w.Add(BRepBuilderAPI_MakeEdge(gp_Pnt(0, 0, 0), pts[0]).Edge())
        w.Add(BRepBuilderAPI_MakeEdge(it.Curve()).Edge())
        w.Add(BRepBuilderAPI_MakeEdge(pts[-1], gp_Pnt(0, 0, b["h"])).Edge())
        w.Add(BRepBuilderAPI_MakeEdge(gp_Pnt(0, 0, b["h"]), gp_Pnt(0, 0, 0)).Edge())
        face = BRepBuilderAPI_MakeFace(w.Wire(), True).Face()
        return BRepPrimAPI_MakeRevol(face, gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), math.radians(b["angle"])).Shape()
    if k == "extrude_spline":
        face = BRepBuilderAPI_MakeFace(_wire_of_curve(_spline_closed(_star(b["r"]))), True).Face()
        if b["taper"]:  # a ruled loft to a smaller copy of the profile
            ts = BRepOffsetAPI_ThruSections(True, True, 1e-6)
            ts.AddWire(_wire_of_curve(_spline_closed(_star(b["r"]))))
            ts.AddWire(_wire_of_curve(_spline_closed(_star([r * 0.8 for r in b["r"]], b["h"]))))
            ts.Build()
            return ts.Shape()
        return BRepPrimAPI_MakePrism(face, gp_Vec(0, 0, b["h"])).Shape()
    if k == "spring":
        from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
        from OCP.gp import gp_Circ

        spine = _helix_edge(b["R"], b["pitch"], b["turns"])
        circ = gp_Circ(gp_Ax2(gp_Pnt(b["R"], 0, 0), gp_Dir(0, 1, 0)), b["wire"])
        prof = _wire_of_curve_edge(BRepBuilderAPI_MakeEdge(circ).Edge())
        return _sweep(prof, spine)
    if k == "thread":
        from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse

        R, p = b["R"], b["pitch"]
        depth = 0.55 * p
        core_r = R - depth
        length = b["turns"] * p
        spine = _helix_edge(core_r * 0.98, p, b["turns"])
        # V profile in the plane through the axis (x-z), its base inside the core
        prof = _polygon_wire([gp_Pnt(core_r * 0.98 - 0.05 * p, 0, -0.4 * p), gp_Pnt(R, 0, -0.02 * p),
                              gp_Pnt(R, 0, 0.02 * p), gp_Pnt(core_r * 0.98 - 0.05 * p, 0, 0.4 * p)])
        thread = _sweep(prof, spine)
        core = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -0.5 * p), gp_Dir(0, 0, 1)), core_r, length + p).Shape()
        body = _checked_bool(BRepAlgoAPI_Fuse(core, thread))
        if b["head"]:
            head = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -0.5 * p - 0.7 * R), gp_Dir(0, 0, 1)), 1.6 * R, 0.7 * R).Shape()
            body = _checked_bool(BRepAlgoAPI_Fuse(body, head))
        return body
    if k == "text":
        return _text(b)
    raise ValueError(k)


def _wire_of_curve_edge(e):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeWire

    return BRepBuilderAPI_MakeWire(e).Wire()


def _text(b):
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.Font import Font_FontAspect_Regular
    from OCP.gp import gp_Ax3, gp_Vec
    from OCP.StdPrs import StdPrs_BRepFont, StdPrs_BRepTextBuilder
    from OCP.NCollection import NCollection_String as NCollection_Utf8String
    from OCP.Graphic3d import Graphic3d_HTA_LEFT, Graphic3d_VTA_BOTTOM

    path = _font()
    if path is None:
        raise Dropped("no font installed (DejaVuSans.ttf)")
    font = StdPrs_BRepFont()
    if not font.Init(NCollection_Utf8String(path), b["size"], 0):
        raise Dropped("font %s did not load" % path)
    shape = StdPrs_BRepTextBuilder().Perform(font, NCollection_Utf8String(b["text"]), gp_Ax3(),
                                             Graphic3d_HTA_LEFT, Graphic3d_VTA_BOTTOM)
    return BRepPrimAPI_MakePrism(shape, gp_Vec(0, 0, b["h"])).Shape()


def _checked_bool(op):
    op.Build()
    if not op.IsDone():
        raise Dropped("boolean failed")
    return op.Shape()


def _edges(shape):
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp
    from OCP.OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as ShapeMap

    from OCP.TopoDS import TopoDS

    m = ShapeMap()
    TopExp.MapShapes_s(shape, TopAbs_EDGE, m)
    return [TopoDS.Edge(m.FindKey(i)) for i in range(1, m.Extent() + 1)]


def _faces(shape):
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp
    from OCP.OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as ShapeMap

    from OCP.TopoDS import TopoDS

    m = ShapeMap()
    TopExp.MapShapes_s(shape, TopAbs_FACE, m)
    return [TopoDS.Face(m.FindKey(i)) for i in range(1, m.Extent() + 1)]


def _pick(items, n, seed):
    rng = random.Random(seed)
    idx = list(range(len(items)))
    rng.shuffle(idx)
    return [items[i] for i in sorted(idx[:n])]


def _bbox(shape):
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    bb = Bnd_Box()
    BRepBndLib.Add_s(shape, bb, False)
    return bb.CornerMin().Coord() + bb.CornerMax().Coord()


def apply_op(shape, o):
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Common, BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse
    from OCP.BRepFilletAPI import BRepFilletAPI_MakeChamfer, BRepFilletAPI_MakeFillet
    from OCP.BRepOffsetAPI import BRepOffsetAPI_DraftAngle, BRepOffsetAPI_MakeThickSolid
    from OCP.OCP.collections import List_TopoDS_Shape as TopTools_ListOfShape
    from OCP.gp import gp_Dir, gp_Pln, gp_Pnt

    k = o["op"]
    if k in ("fuse", "cut", "common"):
        x0, y0, z0, x1, y1, z1 = _bbox(shape)
        t = o["tool"]
        tool = build_base(t)
        # place the tool's centre at a point of the body's box (loc[3:] are box fractions)
        tx0, ty0, tz0, tx1, ty1, tz1 = _bbox(tool)
        from OCP.gp import gp_Trsf, gp_Vec

        c = gp_Trsf()
        c.SetTranslation(gp_Vec(-(tx0 + tx1) / 2, -(ty0 + ty1) / 2, -(tz0 + tz1) / 2))
        rot = _trsf(t["loc"][:3] + [0, 0, 0])
        f = t["loc"][3:]
        mv = gp_Trsf()
        mv.SetTranslation(gp_Vec((x0 + x1) / 2 + f[0] * (x1 - x0), (y0 + y1) / 2 + f[1] * (y1 - y0), (z0 + z1) / 2 + f[2] * (z1 - z0)))
        tool = _moved(tool, mv.Multiplied(rot.Multiplied(c)))
        cls = {"fuse": BRepAlgoAPI_Fuse, "cut": BRepAlgoAPI_Cut, "common": BRepAlgoAPI_Common}[k]
        return _checked_bool(cls(shape, tool))
    if k in ("fillet", "variable_fillet"):
        mk = BRepFilletAPI_MakeFillet(shape)
        for e in _pick(_edges(shape), o["edges"], o["pick"]):
            if k == "fillet":
                mk.Add(o["r"], e)
            else:
                mk.Add(o["r1"], o["r2"], e)
        mk.Build()
        if not mk.IsDone():
            raise Dropped("fillet failed")
        return mk.Shape()
    if k == "chamfer":
        mk = BRepFilletAPI_MakeChamfer(shape)
        for e in _pick(_edges(shape), o["edges"], o["pick"]):
            mk.Add(o["d"], e)
        mk.Build()
        if not mk.IsDone():
            raise Dropped("chamfer failed")
        return mk.Shape()
    if k in ("shell", "offset"):
        mk = BRepOffsetAPI_MakeThickSolid()
        faces = TopTools_ListOfShape()
        if k == "shell":
            fs = _faces(shape)
            faces.Append(_pick(fs, 1, o["pick"])[0])
            mk.MakeThickSolidByJoin(shape, faces, o["t"], 1e-3)
        else:
            from OCP.BRepOffsetAPI import BRepOffsetAPI_MakeOffsetShape

            mo = BRepOffsetAPI_MakeOffsetShape()
            mo.PerformByJoin(shape, o["d"], 1e-3)
            if not mo.IsDone():
                raise Dropped("offset failed")
            return mo.Shape()
        if not mk.IsDone():
            raise Dropped("shell failed")
        return mk.Shape()
    if k == "draft":
        from OCP.GeomAbs import GeomAbs_Plane
        from OCP.BRepAdaptor import BRepAdaptor_Surface

        d = gp_Dir(*o["dir"])
        x0, y0, z0, x1, y1, z1 = _bbox(shape)
        neutral = gp_Pln(gp_Pnt(x0, y0, z0), d)
        mk = BRepOffsetAPI_DraftAngle(shape)
        n = 0
        for f in _faces(shape):
            s = BRepAdaptor_Surface(f)
            if s.GetType() != GeomAbs_Plane:
                continue
            nrm = s.Plane().Axis().Direction()
            if abs(nrm.Dot(d)) < 1e-6:
                mk.Add(f, d, math.radians(o["deg"]), neutral)
                if not mk.AddDone():
                    raise Dropped("draft of a face failed")
                n += 1
        if not n:
            raise Dropped("no planar side face to draft")
        mk.Build()
        if not mk.IsDone():
            raise Dropped("draft failed")
        return mk.Shape()
    raise ValueError(k)


def _valid(shape):
    from OCP.BRepCheck import BRepCheck_Analyzer

    if shape is None or shape.IsNull() or not _faces(shape):
        return False
    return BRepCheck_Analyzer(shape).IsValid()


def build_part(p, dropped, tag, kept):
    try:
        shape = build_base(p["base"])
    except Dropped as e:
        raise Dropped("%s base %s: %s" % (tag, p["base"]["kind"], e))
    except OCCT_ERRORS as e:
        raise Dropped("%s base %s: %s" % (tag, p["base"]["kind"], "%s: %s" % (type(e).__name__, e)))
    if not _valid(shape):
        raise Dropped("%s base %s: invalid shape" % (tag, p["base"]["kind"]))
    for j, o in enumerate(p["ops"]):
        try:
            s2 = apply_op(shape, o)
        except Dropped as e:
            dropped.append("%s op %d %s: %s" % (tag, j, o["op"], e))
            continue
        except OCCT_ERRORS as e:
            dropped.append("%s op %d %s: %s" % (tag, j, o["op"], "%s: %s" % (type(e).__name__, e)))
            continue
        if not _valid(s2):
            dropped.append("%s op %d %s: result invalid" % (tag, j, o["op"]))
            continue
        shape = s2
        kept.append(j)
    return shape


def build_step(rec, path, built_brep=None):
    """Build the recipe with OCCT and write it as STEP (XCAF assembly, names, the recipe's unit
    and schema). Returns {"dropped": [...], "parts": n, "leaves": n, "faces": n (placed),
    "kept": {part: [indices of the operations performed]}}. With `built_brep`, the parts as
    built (OCCT's own format, before any STEP round trip) are also written there, one compound
    of one part each in the order of `"built_parts"` (their names) in the result."""
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.Interface import Interface_Static
    from OCP.STEPCAFControl import STEPCAFControl_Writer
    from OCP.STEPControl import STEPControl_AsIs
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.TDocStd import TDocStd_Document
    from OCP.TopLoc import TopLoc_Location
    from OCP.XCAFDoc import XCAFDoc_DocumentTool

    global OCCT_ERRORS
    OCCT_ERRORS = _occt_errors()
    _quiet()
    dropped = []
    shapes = {}
    kept = {}
    used = sorted({n["part"] for n in _leaves(rec["tree"])})
    for i in used:
        try:
            ops = []
            shapes[i] = build_part(rec["parts"][i], dropped, "part %d" % i, ops)
            kept[i] = ops
        except Dropped as e:
            dropped.append(str(e))
    if not shapes:
        raise Dropped("no part could be built: " + "; ".join(dropped))
    doc = TDocStd_Document(TCollection_ExtendedString("XmlOcaf"))
    try:
        from OCP.UnitsMethods import UnitsMethods_LengthUnit

        XCAFDoc_DocumentTool.SetLengthUnit_s(doc, 1.0, UnitsMethods_LengthUnit.UnitsMethods_LengthUnit_Millimeter)
    except Exception:  # noqa: BLE001
        pass
    st = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    labels = {}
    for i, s in shapes.items():
        lab = st.AddShape(s, False)
        TDataStd_Name.Set_s(lab, TCollection_ExtendedString("part %d" % i))
        labels[i] = lab
    nfaces = [0]

    def add(node, parent_label):
        if "part" in node:
            if node["part"] not in labels:
                return
            c = st.AddComponent(parent_label, labels[node["part"]], TopLoc_Location(_trsf(node["loc"])))
            TDataStd_Name.Set_s(c, TCollection_ExtendedString(node["name"]))
            nfaces[0] += len(_faces(shapes[node["part"]]))
            return
        asm = st.NewShape()
        TDataStd_Name.Set_s(asm, TCollection_ExtendedString(node["name"]))
        for ch in node.get("children", []):
            add(ch, asm)
        if parent_label is not None:
            c = st.AddComponent(parent_label, asm, TopLoc_Location(_trsf(node["loc"])))
            TDataStd_Name.Set_s(c, TCollection_ExtendedString(node["name"]))
        return asm

    add(rec["tree"], None)
    st.UpdateAssemblies()
    Interface_Static.SetCVal_s("write.step.schema", {"AP203": "AP203", "AP214": "AP214IS", "AP242": "AP242DIS"}[rec["schema"]])
    Interface_Static.SetCVal_s("write.step.unit", {"mm": "MM", "inch": "INCH", "m": "M"}[rec["unit"]])
    Interface_Static.SetCVal_s("write.step.product.name", "patchwork generator %d-%d" % (rec["seed"], rec["index"]))
    w = STEPCAFControl_Writer()
    w.SetNameMode(True)
    if not w.Transfer(doc, STEPControl_AsIs):
        raise Dropped("STEP transfer failed")
    tmp = path + ".tmp"
    if w.Write(tmp) != IFSelect_RetDone:
        raise Dropped("STEP write failed")
    os.replace(tmp, path)
    out = {"dropped": dropped, "parts": len(shapes), "leaves": _leaf_count(rec["tree"]), "faces": nfaces[0], "kept": kept}
    if built_brep:
        from OCP.BRep import BRep_Builder
        from OCP.BRepTools import BRepTools
        from OCP.TopoDS import TopoDS_Compound

        b, c = BRep_Builder(), TopoDS_Compound()
        b.MakeCompound(c)
        for i in sorted(shapes):
            b.Add(c, shapes[i])
        if not BRepTools.Write_s(c, built_brep):
            raise Dropped("BRep write failed")
        out["built_parts"] = ["part %d" % i for i in sorted(shapes)]
    return out


def _quiet():
    """OCCT's messenger prints transfer statistics on stdout: silence it."""
    from OCP.Message import Message

    m = Message.DefaultMessenger_s()
    for p in list(m.Printers()):
        m.RemovePrinter(p)


def _leaves(n):
    out = [n] if "part" in n else []
    for c in n.get("children", []):
        out += _leaves(c)
    return out


# ----------------------------------------------------------------------------- main


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--count", type=int, default=10)
    ap.add_argument("--start", type=int, default=0)
    ap.add_argument("--out", default="target/generated")
    ap.add_argument("--describe", action="store_true", help="print each recipe's features, build nothing")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    seen = {}
    for i in range(args.start, args.start + args.count):
        rec = recipe(args.seed, i)
        if args.describe:
            fs = features(rec)
            for f in fs:
                seen[f] = seen.get(f, 0) + 1
            print("gen-%d-%d: %s" % (args.seed, i, " ".join(fs)))
            continue
        step = os.path.join(args.out, "gen-%d-%d.step" % (args.seed, i))
        try:
            info = build_step(rec, step)
        except Dropped as e:
            print("gen-%d-%d: not built (%s)" % (args.seed, i, e))
            continue
        fs = features(rec, info)
        for f in fs:
            seen[f] = seen.get(f, 0) + 1
        with open(step[:-5] + ".json", "w") as fh:
            json.dump(dict(rec, built=info), fh, indent=1)
        print("gen-%d-%d: %d parts, %d placed, %d faces; %s%s" % (args.seed, i, info["parts"], info["leaves"], info["faces"],
                                                             " ".join(fs), ("; dropped: " + "; ".join(info["dropped"])) if info["dropped"] else ""))
    missing = [f for f in FEATURES if f not in seen]
    print("features used: %s" % ", ".join("%s %d" % (f, seen.get(f, 0)) for f in FEATURES))
    if missing:
        print("features not drawn in this range: %s" % ", ".join(missing))
    return 0


if __name__ == "__main__":
    sys.exit(main())
