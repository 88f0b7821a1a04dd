#!/usr/bin/env python3
"""Seeded generator of triangle meshes for the meshoptimizer judge (issue 30: inputs nobody chose).

`recipe(seed, index)` draws a mesh description — plain JSON, so that a failing mesh can be
written down, reduced and rebuilt — and `write(recipe, path_stem)` builds it with numpy (no code
of patchwork's) and writes it as OBJ (with its .mtl when it has materials) or as glTF binary.
The same (seed, index) gives the same recipe and the same file on every machine.

A recipe is a base surface, a displacement and a few modifiers:

  base:    sphere (subdivided icosahedron: closed), grid (open height field), torus
           (genus 1), tube (open cylinder, two border loops), scatter (Delaunay of random
           points: irregular triangles of every shape)
  shape:   bumps (Gaussian, random centres, radii and heights), waves (random Fourier
           modes), crease (a sharp V ridge across the triangles, not along their edges),
           steps (a terrace: a cliff inside triangles), noise (per-vertex jitter: a scan)
  extras:  spikes (thin needles a sampled error misses), holes (discs cut out: inner
           borders), slivers (the surface stretched 1:k, long thin triangles), flip (the
           diagonal of every grid cell chosen at random), seams (OBJ `vt`/`vn` split along
           a seam: the file's vertices are not one per position), materials (faces coloured
           by region: colour borders a renderer must keep), parts (several bodies, one glTF
           node each, touching or interpenetrating)
  frame:   a random rotation, scale (1e-3 .. 1e3) and offset (up to 50 diagonals away)

Reduction (`reduce_recipe`) lowers the resolution, drops extras and shape terms and finally the
frame, keeping each step that still fails a predicate: a failing generated mesh is kept as the
smallest recipe (and file) that still fails.

Command line: `mesh_generator.py --seed S --count N --out DIR` writes DIR/mgen-S-I.obj|.glb and
DIR/mgen-S-I.json; `--describe` prints each recipe.
"""

import argparse
import copy
import json
import math
import os
import random
import struct
import sys

import numpy as np

BASES = ["sphere", "grid", "torus", "tube", "scatter"]
SHAPES = ["bumps", "waves", "crease", "steps", "noise"]
EXTRAS = ["spikes", "holes", "slivers", "flip", "seams", "materials", "parts"]


# ------------------------------------------------------------------------------------ recipes
def recipe(seed, index):
    """The description of mesh `index` of sequence `seed` (JSON-serialisable)."""
    rng = random.Random(f"mesh-{seed}-{index}")
    base = rng.choice(BASES)
    rec = {"seed": seed, "index": index, "base": base}
    # Resolution: 2 000 .. 30 000 triangles or so.
    if base == "sphere":
        rec["level"] = rng.choice([3, 4, 4, 5, 5])
    elif base == "scatter":
        rec["points"] = rng.choice([1500, 3000, 6000, 12000])
    else:
        rec["n"] = rng.choice([40, 60, 90, 120])
        rec["m"] = rng.choice([24, 40, 60, 90]) if base in ("torus", "tube") else rec["n"]
    shapes = []
    for kind in rng.sample(SHAPES, rng.randint(1, 3)):
        s = {"kind": kind, "seed": rng.randrange(1 << 30)}
        if kind == "bumps":
            s["count"] = rng.randint(1, 12)
            s["height"] = rng.uniform(0.02, 0.3)
        elif kind == "waves":
            s["modes"] = rng.randint(1, 6)
            s["height"] = rng.uniform(0.01, 0.15)
            s["max_freq"] = rng.randint(1, 8)
        elif kind == "crease":
            s["height"] = rng.uniform(0.03, 0.3)
        elif kind == "steps":
            s["height"] = rng.uniform(0.02, 0.15)
            s["count"] = rng.randint(1, 4)
        elif kind == "noise":
            s["height"] = rng.choice([1e-4, 1e-3, 5e-3])
        shapes.append(s)
    rec["shapes"] = shapes
    extras = {}
    for kind in EXTRAS:
        if rng.random() < 0.25:
            e = {"seed": rng.randrange(1 << 30)}
            if kind == "spikes":
                e["count"] = rng.randint(1, 5)
                e["height"] = rng.uniform(0.05, 0.5)
            elif kind == "holes":
                e["count"] = rng.randint(1, 3)
                e["radius"] = rng.uniform(0.05, 0.2)
            elif kind == "slivers":
                e["aspect"] = rng.choice([5.0, 20.0, 80.0])
            elif kind == "materials":
                e["count"] = rng.randint(2, 4)
            elif kind == "parts":
                e["count"] = rng.randint(2, 3)
                e["spread"] = rng.uniform(0.3, 1.5)
            extras[kind] = e
    rec["extras"] = extras
    rec["frame"] = {
        "axis": [rng.gauss(0, 1) for _ in range(3)],
        "angle": rng.uniform(0, 2 * math.pi),
        "scale": 10 ** rng.uniform(-3, 3),
        "offset": [rng.uniform(-50, 50) if rng.random() < 0.3 else 0.0 for _ in range(3)],
    }
    return rec


def describe(rec):
    words = [rec["base"]] + [s["kind"] for s in rec["shapes"]] + sorted(rec["extras"])
    return " ".join(words)


# ------------------------------------------------------------------------------- base surfaces
def sphere(level):
    """A subdivided icosahedron on the unit sphere: positions, faces, (u, v) per vertex."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    pos = [np.array(p, float) / np.linalg.norm(p) for p in v]
    faces = f
    for _ in range(level):
        mid = {}
        new = []

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = pos[a] + pos[b]
                pos.append(p / np.linalg.norm(p))
                mid[key] = len(pos) - 1
            return mid[key]

        for a, b, c in faces:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    p = np.array(pos)
    uv = np.stack([np.arctan2(p[:, 1], p[:, 0]) / (2 * np.pi) + 0.5,
                   np.arccos(np.clip(p[:, 2], -1, 1)) / np.pi], axis=1)
    return p, np.array(faces, np.int64), uv


def grid_faces(n, m, rng=None, wrap_u=False, wrap_v=False):
    """Two triangles per cell of an (n+1) x (m+1) vertex grid (indices i * (m + 1) + j), the
    cell diagonal at random when `rng` is given. `wrap_*`: the last row/column is the first."""
    rows, cols = n + (0 if wrap_u else 1), m + (0 if wrap_v else 1)

    def at(i, j):
        return (i % rows) * cols + (j % cols)

    faces = []
    for i in range(n):
        for j in range(m):
            a, b, c, d = at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)
            if rng is not None and rng.random() < 0.5:
                faces += [(a, b, d), (b, c, d)]
            else:
                faces += [(a, b, c), (a, c, d)]
    return np.array(faces, np.int64), rows, cols


def base_surface(rec, rng):
    """Positions, faces and per-vertex (u, v) of the base surface, with its "up" direction per
    vertex (what shapes displace along)."""
    base = rec["base"]
    flip = "flip" in rec["extras"]
    if base == "sphere":
        p, f, uv = sphere(rec["level"])
        return p, f, uv, p.copy()
    if base == "scatter":
        from scipy.spatial import Delaunay
        k = rec["points"]
        border = max(8, int(k ** 0.5))
        s = np.linspace(0, 1, border, endpoint=False)
        edge = np.concatenate([np.stack([s, 0 * s], 1), np.stack([1 + 0 * s, s], 1),
                               np.stack([1 - s, 1 + 0 * s], 1), np.stack([0 * s, 1 - s], 1)])
        inner = np.array([[rng.random(), rng.random()] for _ in range(k)])
        uv = np.concatenate([edge, inner])
        f = Delaunay(uv).simplices.astype(np.int64)
        # Counter-clockwise seen from +z.
        a, b, c = uv[f[:, 0]], uv[f[:, 1]], uv[f[:, 2]]
        cw = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
        f[cw] = f[cw][:, [0, 2, 1]]
        p = np.concatenate([uv * 2 - 1, np.zeros((len(uv), 1))], axis=1)
        return p, f, uv, np.tile([0.0, 0.0, 1.0], (len(p), 1))
    n, m = rec["n"], rec["m"]
    if base == "grid":
        f, rows, cols = grid_faces(n, m, rng if flip else None)
        i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
        uv = np.stack([i.ravel() / n, j.ravel() / m], 1)
        p = np.concatenate([uv * 2 - 1, np.zeros((len(uv), 1))], axis=1)
        return p, f, uv, np.tile([0.0, 0.0, 1.0], (len(p), 1))
    if base == "torus":
        f, rows, cols = grid_faces(n, m, rng if flip else None, wrap_u=True, wrap_v=True)
        i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
        u, v = i.ravel() / n * 2 * np.pi, j.ravel() / m * 2 * np.pi
        big, small = 1.0, 0.35
        centre = np.stack([big * np.cos(u), big * np.sin(u), 0 * u], 1)
        up = np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], 1)
        return centre + small * up, f, np.stack([i.ravel() / n, j.ravel() / m], 1), up
    # tube: open at both ends, wrapped around.
    f, rows, cols = grid_faces(n, m, rng if flip else None, wrap_u=True)
    i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    u, h = i.ravel() / n * 2 * np.pi, j.ravel() / m * 2 - 1
    up = np.stack([np.cos(u), np.sin(u), 0 * u], 1)
    p = 0.6 * up + np.stack([0 * u, 0 * u, h], 1)
    return p, f, np.stack([i.ravel() / n, j.ravel() / m], 1), up


# ------------------------------------------------------------------------------------- shapes
def displacement(rec, p, uv):
    """Height along "up" at every vertex, from the recipe's shape terms."""
    h = np.zeros(len(p))
    for s in rec["shapes"]:
        r = random.Random(s["seed"])
        if s["kind"] == "bumps":
            for _ in range(s["count"]):
                c = p[r.randrange(len(p))]
                width = r.uniform(0.05, 0.5)
                d2 = ((p - c) ** 2).sum(1)
                h += r.choice([-1, 1]) * s["height"] * r.random() * np.exp(-d2 / (2 * width ** 2))
        elif s["kind"] == "waves":
            for _ in range(s["modes"]):
                k = np.array([r.randint(-s["max_freq"], s["max_freq"]) for _ in range(3)], float)
                h += s["height"] / max(1, s["modes"] ** 0.5) * np.sin(p @ k * np.pi + r.uniform(0, 6.3))
        elif s["kind"] == "crease":
            d = np.array([r.gauss(0, 1) for _ in range(3)])
            d /= np.linalg.norm(d)
            h += s["height"] * (0.5 - np.abs(p @ d - r.uniform(-0.3, 0.3)))
        elif s["kind"] == "steps":
            d = np.array([r.gauss(0, 1) for _ in range(3)])
            d /= np.linalg.norm(d)
            for _ in range(s["count"]):
                h += s["height"] * (p @ d > r.uniform(-0.6, 0.6))
        elif s["kind"] == "noise":
            rr = np.random.default_rng(s["seed"])
            h += s["height"] * rr.uniform(-1, 1, len(p))
    return h


def build(rec):
    """The mesh of a recipe: a list of parts, each (positions (k, 3), faces (t, 3), uv (k, 2),
    material per face or None)."""
    rng = random.Random(f"build-{rec['seed']}-{rec['index']}")
    ex = rec["extras"]
    count = ex["parts"]["count"] if "parts" in ex else 1
    parts = []
    for part in range(count):
        p, f, uv, up = base_surface(rec, rng)
        p = p + up * displacement(rec, p, uv)[:, None]
        if "spikes" in ex:
            r = random.Random(ex["spikes"]["seed"] + part)
            for _ in range(ex["spikes"]["count"]):
                k = r.randrange(len(p))
                p[k] = p[k] + up[k] * ex["spikes"]["height"] * r.uniform(0.3, 1.0)
        if "slivers" in ex:
            p[:, 0] *= ex["slivers"]["aspect"] ** 0.5
            p[:, 1] /= ex["slivers"]["aspect"] ** 0.5
        if "holes" in ex:
            r = random.Random(ex["holes"]["seed"] + part)
            centroid = p[f].mean(1)
            keep = np.ones(len(f), bool)
            for _ in range(ex["holes"]["count"]):
                c = centroid[r.randrange(len(f))]
                keep &= ((centroid - c) ** 2).sum(1) > ex["holes"]["radius"] ** 2
            if keep.sum() >= len(f) // 4:
                f = f[keep]
        material = None
        if "materials" in ex:
            r = random.Random(ex["materials"]["seed"] + part)
            d = np.array([r.gauss(0, 1) for _ in range(3)])
            cuts = sorted(r.uniform(-0.8, 0.8) for _ in range(ex["materials"]["count"] - 1))
            material = np.searchsorted(cuts, p[f].mean(1) @ d / np.linalg.norm(d))
        if part > 0:
            r = random.Random(f"part-{rec['seed']}-{rec['index']}-{part}")
            shift = np.array([r.uniform(-1, 1) for _ in range(3)])
            shift *= ex["parts"]["spread"] * 2 / np.linalg.norm(shift)
            p = p * r.uniform(0.4, 1.0) + shift
        # Only referenced vertices.
        used = np.unique(f)
        remap = np.full(len(p), -1)
        remap[used] = np.arange(len(used))
        parts.append((p[used], remap[f], uv[used], material))
    fr = rec["frame"]
    axis = np.array(fr["axis"], float)
    axis /= np.linalg.norm(axis) if np.linalg.norm(axis) > 0 else 1.0
    rot = rotation(axis, fr["angle"])
    size = max(float(np.linalg.norm(np.ptp(np.concatenate([q[0] for q in parts]), 0))), 1e-9)
    out = []
    for p, f, uv, mat in parts:
        q = (p @ rot.T) * fr["scale"] + np.array(fr["offset"]) * size * fr["scale"]
        out.append((q, f, uv, mat))
    return out


def rotation(axis, angle):
    x, y, z = axis
    c, s = math.cos(angle), math.sin(angle)
    k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + s * k + (1 - c) * (k @ k)


# ------------------------------------------------------------------------------------- writers
def write(rec, stem):
    """Writes the recipe's mesh: `stem.glb` when it has several parts, else `stem.obj` (and
    `stem.mtl` with materials). Returns the path written."""
    parts = build(rec)
    if len(parts) > 1:
        path = stem + ".glb"
        write_glb(parts, path)
    else:
        path = stem + ".obj"
        write_obj(parts[0], path, seams="seams" in rec["extras"], rec=rec)
    return path


def palette(k):
    return [(0.8, 0.3, 0.2), (0.2, 0.6, 0.3), (0.2, 0.3, 0.8), (0.8, 0.7, 0.2)][k % 4]


def write_obj(part, path, seams, rec):
    p, f, uv, mat = part
    lines = []
    mtl = None
    if mat is not None:
        mtl = os.path.splitext(path)[0] + ".mtl"
        with open(mtl, "w") as out:
            for k in range(int(mat.max()) + 1):
                out.write("newmtl m%d\nKd %.3f %.3f %.3f\n" % ((k,) + palette(k)))
        lines.append("mtllib %s" % os.path.basename(mtl))
    lines += ["v %.9g %.9g %.9g" % tuple(x) for x in p]
    if seams:
        # Texture coordinates wrapped at u = 0.5 and flat normals per face: the file's
        # vertices split along a seam line and at every face for `vn`.
        r = random.Random(rec["extras"]["seams"]["seed"])
        lines += ["vt %.6f %.6f" % tuple(x) for x in uv]
        lines += ["vt %.6f %.6f" % (x[0] + 1.0, x[1]) for x in uv]
        n = np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
        flat = r.random() < 0.5
        if flat:
            lines += ["vn %.6f %.6f %.6f" % tuple(x) for x in n]
    current = None
    for t, tri in enumerate(f):
        if mat is not None and mat[t] != current:
            current = mat[t]
            lines.append("usemtl m%d" % current)
        if seams:
            u = uv[tri, 0]
            wrap = u.max() - u.min() > 0.5 or (u < 0.5).any() and (u >= 0.5).any()
            vt = [i + 1 + (len(uv) if wrap and uv[i, 0] < 0.5 else 0) for i in tri]
            if flat:
                lines.append("f " + " ".join("%d/%d/%d" % (i + 1, j, t + 1) for i, j in zip(tri, vt)))
            else:
                lines.append("f " + " ".join("%d/%d" % (i + 1, j) for i, j in zip(tri, vt)))
        else:
            lines.append("f %d %d %d" % tuple(tri + 1))
    with open(path, "w") as out:
        out.write("\n".join(lines) + "\n")


def write_glb(parts, path):
    """glTF 2.0 binary: one node, mesh and primitive per part (its own material colour), or
    one primitive per material of a part."""
    blob = bytearray()
    views, accessors, meshes, nodes, materials = [], [], [], [], []

    def add(data, target):
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data),
                      "target": target})
        blob.extend(data)
        return len(views) - 1

    for k, (p, f, _, mat) in enumerate(parts):
        pos = p.astype(np.float32)
        v = add(pos.tobytes(), 34962)
        accessors.append({"bufferView": v, "componentType": 5126, "count": len(pos),
                          "type": "VEC3", "min": pos.min(0).tolist(), "max": pos.max(0).tolist()})
        a_pos = len(accessors) - 1
        prims = []
        groups = [(None, f)] if mat is None else [(m, f[mat == m]) for m in np.unique(mat)]
        for m, ff in groups:
            idx = ff.astype(np.uint32).ravel()
            v = add(idx.tobytes(), 34963)
            accessors.append({"bufferView": v, "componentType": 5125, "count": len(idx),
                              "type": "SCALAR"})
            colour = palette(k if m is None else int(m) + k)
            materials.append({"pbrMetallicRoughness": {"baseColorFactor": list(colour) + [1.0]}})
            prims.append({"attributes": {"POSITION": a_pos}, "indices": len(accessors) - 1,
                          "material": len(materials) - 1})
        meshes.append({"primitives": prims})
        nodes.append({"mesh": k})
    while len(blob) % 4:
        blob.append(0)
    doc = {"asset": {"version": "2.0", "generator": "patchwork tools/mesh_generator.py"},
           "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes,
           "meshes": meshes, "materials": materials, "accessors": accessors,
           "bufferViews": views, "buffers": [{"byteLength": len(blob)}]}
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    with open(path, "wb") as out:
        out.write(struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(blob)))
        out.write(struct.pack("<II", len(js), 0x4E4F534A) + js)
        out.write(struct.pack("<II", len(blob), 0x004E4942) + bytes(blob))


# ----------------------------------------------------------------------------------- reduction
def simpler(rec):
    """Recipes one step simpler than `rec`, most reducing first."""
    out = []
    r = copy.deepcopy(rec)
    if r["base"] == "sphere" and r["level"] > 2:
        r["level"] -= 1
        out.append(r)
    elif r["base"] == "scatter" and r["points"] > 200:
        r["points"] //= 2
        out.append(r)
    elif r["base"] not in ("sphere", "scatter") and min(r["n"], r["m"]) > 8:
        r["n"], r["m"] = max(8, r["n"] // 2), max(8, r["m"] // 2)
        out.append(r)
    for kind in list(rec["extras"]):
        r = copy.deepcopy(rec)
        del r["extras"][kind]
        out.append(r)
    for k in range(len(rec["shapes"])):
        if len(rec["shapes"]) > 1:
            r = copy.deepcopy(rec)
            del r["shapes"][k]
            out.append(r)
    fr = rec["frame"]
    if fr["angle"] != 0.0 or fr["scale"] != 1.0 or any(fr["offset"]):
        r = copy.deepcopy(rec)
        r["frame"] = {"axis": [0.0, 0.0, 1.0], "angle": 0.0, "scale": 1.0, "offset": [0.0] * 3}
        out.append(r)
    return out


def reduce_recipe(rec, fails, log=print):
    """The smallest recipe reached from `rec` by `simpler` steps for which `fails(recipe)` holds
    (`fails(rec)` is assumed)."""
    changed = True
    while changed:
        changed = False
        for r in simpler(rec):
            if fails(r):
                log("  reduced to: " + describe(r))
                rec, changed = r, True
                break
    return rec


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--start", type=int, default=0)
    ap.add_argument("--count", type=int, default=10)
    ap.add_argument("--out", default=None)
    ap.add_argument("--describe", action="store_true")
    args = ap.parse_args()
    for i in range(args.start, args.start + args.count):
        rec = recipe(args.seed, i)
        name = f"mgen-{args.seed}-{i}"
        if args.describe or not args.out:
            print(name, describe(rec))
        if args.out:
            os.makedirs(args.out, exist_ok=True)
            stem = os.path.join(args.out, name)
            path = write(rec, stem)
            with open(stem + ".json", "w") as out:
                json.dump(rec, out, indent=1)
            print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
