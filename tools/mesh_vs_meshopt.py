#!/usr/bin/env python3
"""Our mesh simplification beside meshoptimizer's at equal triangle counts (issue 30).

    pip install meshoptimizer trimesh rtree scipy numpy
    python3 tools/mesh_vs_meshopt.py models/bunny.glb --rel 0.005,0.01,0.02

For every relative tolerance rel (T = rel x the mesh's bounding-box diagonal):
`patchwork export MODEL --tolerance T --unit model --up model --no-cache`, then meshoptimizer's
`simplify` of the whole original mesh to the same triangle count, and each result's two-sided
Hausdorff distance to the original (100 000 area-weighted surface samples plus every vertex,
both ways, exact closest points through trimesh), printed relative to the diagonal with the
ratio ours / meshopt. The original is read by trimesh itself (no code of ours between the
file and the judge; node transforms applied, the model's own units and axes as `--unit model
--up model` writes) and welded by position, so meshoptimizer sees one mesh without patch
borders; our export reaching outside the original's bounding box (by 1e-6 of the diagonal)
stops the run: its vertices are the original's, so the two would not be in the same frame.

`--keep-parts`: meshoptimizer gets the borders between the file's primitives (glTF
primitives: one colour or material each) as open borders instead, each primitive welded on
its own and the primitives concatenated, so it may simplify along them but not across them
— the constraint our patches have (a patch never crosses a part or colour). A renderer must
keep those borders: collapsing across one moves a colour boundary. The distances are still to
the whole welded original. Without primitives (OBJ, PLY, one primitive) the two are the same.

As a judge (CI runs it on every shipped mesh): the run fails (exit 1) when our sampled
Hausdorff distance exceeds the tolerance T asked for (every cut is certified within T, so a
sample beyond it is a broken bound; float32 positions allow 1e-5 of T), or, with
`--max-ratio R`, when ours / meshopt exceeds R — except for the (model, rel) pairs listed in
`--known-failures FILE` (lines `MODEL REL  reason`; MODEL as given on the command line),
which are reported KNOWN. `--mutate K` moves every vertex of our export by K·T in a random
direction before it is measured: a broken simplifier the judge must catch (CI runs it and
requires exit 1).
"""

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import trimesh

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def load(path):
    m = trimesh.load(path, process=False)
    if isinstance(m, trimesh.Scene):
        m = m.to_geometry()
    return m


def one_sided(a, b, n, seed):
    pts, _ = trimesh.sample.sample_surface(a, n, seed=seed)
    pts = np.vstack([pts, a.vertices[np.unique(a.faces)]])
    worst = 0.0
    for i in range(0, len(pts), 20000):
        _, d, _ = trimesh.proximity.closest_point(b, pts[i:i + 20000])
        worst = max(worst, float(d.max()))
    return worst


def by_parts(path):
    """The file's primitives, each welded on its own and placed, concatenated (not welded
    together: their shared borders stay open for meshoptimizer)."""
    scene = trimesh.load(path, process=False)
    if not isinstance(scene, trimesh.Scene):
        scene.merge_vertices(merge_tex=True, merge_norm=True)
        return scene
    parts = []
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        g = scene.geometry[name].copy()
        g.apply_transform(transform)
        g.remove_unreferenced_vertices()
        g.merge_vertices(merge_tex=True, merge_norm=True)
        parts.append(g)
    return trimesh.util.concatenate(parts)


def hausdorff(a, b, n=100000):
    return max(one_sided(a, b, n, 1), one_sided(b, a, n, 2))


def export(patchwork, model, out, tolerance):
    subprocess.run([patchwork, "export", model, "-q", "--no-cache", "-o", out, "--tolerance",
                    repr(tolerance), "--unit", "model", "--up", "model"], check=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model")
    ap.add_argument("--rel", default="0.005,0.01,0.02")
    ap.add_argument("--keep-parts", action="store_true",
                    help="meshoptimizer keeps the borders between the file's primitives")
    ap.add_argument("--patchwork", default=os.environ.get(
        "PATCHWORK", os.path.join(REPO, "target", "release", "patchwork")))
    ap.add_argument("--max-ratio", type=float, default=None,
                    help="fail when ours / meshopt exceeds this (issue 30's goal: 1.0)")
    ap.add_argument("--known-failures", default=None,
                    help="file of `MODEL REL  reason` lines reported KNOWN, not failed")
    ap.add_argument("--mutate", type=float, default=0.0,
                    help="move our vertices by this many T at random (the judge must fail)")
    args = ap.parse_args()
    known = set()
    if args.known_failures:
        with open(args.known_failures) as f:
            for line in f:
                words = line.split()
                if len(words) >= 2 and not words[0].startswith("#"):
                    known.add((words[0], float(words[1])))
    failures = []
    import meshoptimizer

    with tempfile.TemporaryDirectory() as tmp:
        orig = load(args.model)
        # One vertex per position (a file splits vertices at UV and normal seams, which
        # meshoptimizer would read as open borders and lock).
        orig.merge_vertices(merge_tex=True, merge_norm=True)
        diag = float(np.linalg.norm(orig.bounds[1] - orig.bounds[0]))
        print(f"{args.model}: {len(orig.faces)} triangles, diagonal {diag:.4g}")
        print(f"{'T/diag':>8} {'triangles':>10} {'ours H/diag':>12} {'meshopt H/diag':>15} {'ratio':>6}")
        given = by_parts(args.model) if args.keep_parts else orig
        if args.keep_parts:
            print(f"meshoptimizer keeps the borders of the primitives: {len(given.vertices)} "
                  f"vertices against {len(orig.vertices)} welded")
        indices = given.faces.astype(np.uint32).ravel()
        verts = given.vertices.astype(np.float32)
        for rel in [float(x) for x in args.rel.split(",")]:
            out = os.path.join(tmp, f"ours-{rel}.glb")
            export(args.patchwork, args.model, out, rel * diag)
            ours = load(out)
            # Our vertices are the original's (half-edge collapses): outside its box, the two
            # are not in the same frame.
            off = float(max((orig.bounds[0] - ours.bounds[0]).max(),
                            (ours.bounds[1] - orig.bounds[1]).max()))
            if off > 1e-6 * diag:
                sys.exit(f"our export reaches {off:.3g} outside the original's box: "
                         "not the same frame")
            n = len(ours.faces)
            if args.mutate:
                rng = np.random.default_rng(3)
                step = rng.normal(size=ours.vertices.shape)
                step /= np.linalg.norm(step, axis=1, keepdims=True)
                ours = trimesh.Trimesh(ours.vertices + step * args.mutate * rel * diag,
                                       ours.faces, process=False)
            dst = np.zeros(indices.size, dtype=np.uint32)
            k = meshoptimizer.simplify(dst, indices, verts, target_index_count=3 * n,
                                       target_error=1.0)
            theirs = trimesh.Trimesh(given.vertices, dst[:k].reshape(-1, 3), process=False)
            h_ours, h_theirs = hausdorff(ours, orig) / diag, hausdorff(theirs, orig) / diag
            ratio = h_ours / h_theirs
            verdict = []
            if h_ours > rel * (1 + 1e-5):
                verdict.append(f"ours {h_ours:.3e} is beyond the tolerance {rel:g}: "
                               "the certified bound is broken")
            if args.max_ratio is not None and ratio > args.max_ratio:
                verdict.append(f"ratio {ratio:.3f} > {args.max_ratio:g}")
            mark = ""
            if not verdict and (args.model, rel) in known:
                mark = "  NOW PASSES: remove it from the known failures"
            if verdict:
                if (args.model, rel) in known and not any("certified" in v for v in verdict):
                    mark = "  KNOWN: " + "; ".join(verdict)
                else:
                    mark = "  FAIL: " + "; ".join(verdict)
                    failures.append(f"{args.model} at {rel:g}: " + "; ".join(verdict))
            print(f"{rel:>8g} {n:>10} {h_ours:>12.2e} {h_theirs:>15.2e} {ratio:>6.3f}"
                  f"   (meshopt {len(theirs.faces)} triangles){mark}", flush=True)
    for f in failures:
        print("FAIL", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
