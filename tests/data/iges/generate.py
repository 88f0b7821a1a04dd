#!/usr/bin/env python3
"""Writes the small IGES 5.3 files of tests/iges.rs (fixed format, 80 columns).

The base model: a 10 x 10 mm square (a bilinear 128) trimmed (144) by an outer boundary (142:
four 110 lines in parameter space and in model space) and a hole (142: a full 100 circle of
radius 2 about the centre, in both spaces), placed by a 124 (90 degrees about z, then 100 mm
along x) and coloured by a 314. Each other file changes one thing. Run from anywhere:
`python3 tests/data/iges/generate.py`.
"""

import os

HERE = os.path.dirname(os.path.abspath(__file__))


def holl(s):
    return "%dH%s" % (len(s), s)


def wrap(tokens, width, pd, rd):
    """Tokens joined by pd and ended by rd, cut into lines of at most `width` at delimiters."""
    lines, cur = [], ""
    for i, t in enumerate(tokens):
        piece = t + (rd if i == len(tokens) - 1 else pd)
        if len(cur) + len(piece) > width:
            lines.append(cur)
            cur = ""
        cur += piece
    lines.append(cur)
    return lines


def write(name, entities, pd=",", rd=";", unit=(2, "MM"), product="patchwork test", truncate=None,
          short_line=None):
    """entities: list of dicts type, params (strings), and optional form, transform, color,
    status. `truncate`: index of an entity whose record delimiter is dropped; `short_line`: a
    1-based line to cut to 79 columns."""
    g = [holl(pd), holl(rd), holl(product), holl(name), holl("generate.py"), holl("1"), "32", "38", "6",
         "308", "15", holl(product), "1.", str(unit[0]), holl(unit[1]), "1", "0.", holl("20261127.000000"),
         "1.E-6", "100.", holl("patchwork"), holl("tests"), "11", "0"]
    glines = wrap(g, 72, pd, rd)
    d, p = [], []
    for i, e in enumerate(entities):
        de = 2 * i + 1
        toks = [str(e["type"])] + [str(x) for x in e["params"]]
        plines = wrap(toks, 64, pd, rd)
        if truncate == i:
            plines[-1] = plines[-1][:-1]
        first = len(p) + 1
        for l in plines:
            p.append("%-64s%8d" % (l, de))
        status = e.get("status", "00000000")
        d.append("%8d%8d%8d%8d%8d%8d%8d%8d%8s" % (e["type"], first, 0, 0, 0, 0, e.get("transform", 0), 0, status))
        d.append("%8d%8d%8d%8d%8d%8s%8s%8s%8d" % (e["type"], 0, e.get("color", 0), len(plines), e.get("form", 0), "", "",
                                                   "", 0))
    out = ["%-72sS%7d" % ("patchwork IGES test file " + name, 1)]
    out += ["%-72sG%7d" % (l, k + 1) for k, l in enumerate(glines)]
    out += ["%-72sD%7d" % (l, k + 1) for k, l in enumerate(d)]
    out += ["%-72sP%7d" % (l, k + 1) for k, l in enumerate(p)]
    out.append("%-72sT%7d" % ("S%7dG%7dD%7dP%7d" % (1, len(glines), len(d), len(p)), 1))
    if short_line:
        out[short_line - 1] = out[short_line - 1][:79]
    with open(os.path.join(HERE, name), "w") as f:
        f.write("\n".join(out) + "\n")


def line(a, b):
    return {"type": 110, "params": [*a, *b], "status": "00010000"}


def circle(c, r, z=0.0):
    s = (c[0] + r, c[1])
    return {"type": 100, "params": [z, c[0], c[1], s[0], s[1], s[0], s[1]], "status": "00010000"}


def composite(first, n):
    return {"type": 102, "params": [n] + [first + 2 * k for k in range(n)], "status": "00010000"}


def square(size):
    c = [(0, 0, 0), (size, 0, 0), (size, size, 0), (0, size, 0)]
    return [line(c[k], c[(k + 1) % 4]) for k in range(4)]


def plane128(size=10.0):
    pts = [(0, 0, 0), (size, 0, 0), (0, size, 0), (size, size, 0)]
    return {"type": 128, "status": "00010000",
            "params": [1, 1, 1, 1, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 1, 1, 1, 1, 1, 1]
            + [x for p in pts for x in p] + [0, 1, 0, 1]}


def base(hole=True, inner_cptr=None, inner_bptr=None, pti=None, extra=()):
    """Entities of the base model; DE numbers are 2 k + 1 for entity k."""
    e = [None] * 24
    # 1: trimmed surface, 3: surface, 5: outer 142, 7: inner 142
    e[0] = {"type": 144, "params": [3, 1, 1 if hole else 0, 5] + ([7 if pti is None else pti] if hole else []),
            "transform": 41, "color": -43}
    e[1] = plane128()
    e[2] = {"type": 142, "params": [1, 3, 9, 19, 1], "status": "00010500"}
    e[3] = {"type": 142, "params": [1, 3, 29 if inner_bptr is None else inner_bptr,
                                    31 if inner_cptr is None else inner_cptr, 1], "status": "00010500"}
    # 9: parameter-space composite of 11..17; 19: model-space composite of 21..27
    e[4] = composite(11, 4)
    e[5:9] = square(1.0)
    e[9] = composite(21, 4)
    e[10:14] = square(10.0)
    # 29: parameter-space circle, 31: model-space circle
    e[14] = circle((0.5, 0.5), 0.2)
    e[15] = circle((5.0, 5.0), 2.0)
    # 33..39: spare (a self-referencing composite for the cycle test)
    e[16] = {"type": 102, "params": [1, 33], "status": "00010000"}
    e[17] = circle((0.5, 0.5), 0.3)  # 35: a parameter-space circle that strays from 31
    e[18] = {"type": 110, "params": [0, 0, 0, 1, 0, 0], "status": "00010000"}
    e[19] = {"type": 110, "params": [0, 0, 0, 1, 0, 0], "status": "00010000"}
    # 41: 90 degrees about z, then (100, 0, 0); 43: colour
    e[20] = {"type": 124, "params": [0, -1, 0, 100, 1, 0, 0, 0, 0, 0, 1, 0], "status": "00010000"}
    e[21] = {"type": 314, "params": [20, 40, 60, holl("BLUE/GREY#")], "status": "00010000"}
    e[22] = {"type": 402, "params": [1, 1], "form": 7}
    e[23] = {"type": 406, "params": [1, holl("x")], "form": 15, "status": "00010000"}
    return e + list(extra)


def main():
    write("square_hole.igs", base())
    write("square_hole_inch.igs", base(), unit=(1, "IN"))
    write("square_hole_delimiters.igs", base(), pd="/", rd="#", product="a/b#c, d;e")
    write("square_hole_stray_pcurve.igs", base(inner_bptr=35))
    write("bad_pointer.igs", base(pti=99))
    write("cycle.igs", base(inner_cptr=33, inner_bptr=0))
    write("truncated.igs", base(), truncate=1)
    missing = base()
    missing[1] = dict(missing[1], params=missing[1]["params"][:25])
    write("missing_parameter.igs", missing)
    write("short_line.igs", base(), short_line=6)
    # One good face and one whose hole points nowhere: the good one is drawn.
    two = base()
    two.append(dict(two[0], params=[3, 1, 1, 5, 97]))
    write("one_bad_face.igs", two)
    # An untrimmed 128 drawn whole (independent, used by no 144).
    write("untrimmed.igs", [dict(plane128(4.0), status="00000000")])
    # The trimmed square as a subfigure (308, members physically dependent) placed twice (408).
    sub = base()
    sub[0] = dict(sub[0], status="00010000", transform=0)
    sub += [
        {"type": 308, "params": [0, holl("SQUARE"), 1, 1], "status": "00010200"},
        {"type": 408, "params": [49, 0, 0, 0, 1]},
        {"type": 408, "params": [49, 0, 20, 0, 2]},
    ]
    write("subfigures.igs", sub)
    # The square on planes: a 108 (z = 0) and a 190 (point 116, normal and reference 123). Their
    # parameter spaces are not the 128's unit square: the model-space curves trim them.
    p108 = base()
    p108[1] = {"type": 108, "params": [0, 0, 1, 0, 0, 0, 0, 0, 0], "status": "00010000"}
    write("plane_108.igs", p108)
    p190 = base(extra=[{"type": 116, "params": [0, 0, 0], "status": "00010000"},
                       {"type": 123, "params": [0, 0, 1], "status": "00010000"},
                       {"type": 123, "params": [1, 0, 0], "status": "00010000"}])
    p190[1] = {"type": 190, "params": [49, 51, 53], "form": 1, "status": "00010000"}
    write("plane_190.igs", p190)


if __name__ == "__main__":
    main()
