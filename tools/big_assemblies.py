#!/usr/bin/env python3
"""Writes two large STEP assemblies through Open CASCADE from public files in `models/corpus`.

Issue 31 asks for convergence figures on "two more public assemblies of >= 10 000 faces" besides
the three KiCad boards of the corpus. No public STEP file of that size is in the repository
(models/corpus/LICENSES.md: the largest shipped model found has 4 852 faces), and committing
multi-megabyte files to keep two bench inputs is not worth the repository's size. So they are
made here, reproducibly, by OCCT (a writer that shares no code with patchwork), from the
corpus's public files, and written to an output directory (default target/assemblies):

  boards-22k.step  the three KiCad boards side by side (8 766 + 5 469 + 8 613 = 22 848 faces):
                   one OCCT-written assembly of three board assemblies.
  parts-14k.step   the five largest single parts, each once (Molex SlimStack 4 852, DIN41612
                   3 980, PQFP-256 3 879, tough_second_order 929, Block 533 = 14 173 faces):
                   few shared placements, so every face is its own tessellation.

Licences: those of the files used (models/corpus/LICENSES.md).

Usage: python tools/big_assemblies.py [OUT_DIR]   (needs cadquery-ocp: tools/occt_requirements.txt)
"""

import gzip
import os
import sys
import tempfile

from OCP.BRep import BRep_Builder
from OCP.Bnd import Bnd_Box
from OCP.BRepBndLib import BRepBndLib
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Reader, STEPControl_Writer
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS_Compound
from OCP.gp import gp_Trsf, gp_Vec

HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "..", "models", "corpus")

SETS = {
    "boards-22k.step": [
        "kicad-demo-kit-dev-coldfire-xilinx_5213.step.gz",
        "kicad-demo-tinytapeout.step.gz",
        "kicad-demo-video.step.gz",
    ],
    "parts-14k.step": [
        "Molex_SlimStack_54722-0804_2x40_P0.50mm_Vertical.step.gz",
        "DIN41612_C_3x32_Male_Horizontal_THT.step.gz",
        "PQFP-256_28x28mm_P0.4mm.step.gz",
        "tough_second_order.step.gz",
        "Block.stp.gz",
    ],
}


def read(path):
    """The file's whole shape (one compound of its roots), read by OCCT."""
    with tempfile.TemporaryDirectory() as tmp:
        plain = path
        if path.endswith(".gz"):
            plain = os.path.join(tmp, os.path.basename(path)[:-3])
            with gzip.open(path, "rb") as src, open(plain, "wb") as dst:
                dst.write(src.read())
        reader = STEPControl_Reader()
        if reader.ReadFile(plain) != IFSelect_RetDone:
            raise SystemExit(f"{path}: OCCT could not read it")
        reader.TransferRoots()
        return reader.OneShape()


def faces(shape):
    n, e = 0, TopExp_Explorer(shape, TopAbs_FACE)
    while e.More():
        n += 1
        e.Next()
    return n


def extent(shape):
    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box)
    return box.CornerMin().X(), box.CornerMax().X()


def assemble(names):
    """The files side by side along x, 10 % of the widest apart."""
    builder, out = BRep_Builder(), TopoDS_Compound()
    builder.MakeCompound(out)
    shapes = [read(os.path.join(CORPUS, n)) for n in names]
    widths = [extent(s) for s in shapes]
    gap = 0.1 * max(x1 - x0 for x0, x1 in widths)
    x = 0.0
    total = 0
    for name, shape, (x0, x1) in zip(names, shapes, widths):
        t = gp_Trsf()
        t.SetTranslation(gp_Vec(x - x0, 0.0, 0.0))
        builder.Add(out, shape.Moved(TopLoc_Location(t)))
        x += (x1 - x0) + gap
        n = faces(shape)
        total += n
        print(f"  {name}: {n} faces")
    return out, total


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "..", "target", "assemblies")
    os.makedirs(out_dir, exist_ok=True)
    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    Interface_Static.SetIVal_s("write.step.assembly", 1)
    for name, parts in SETS.items():
        shape, total = assemble(parts)
        writer = STEPControl_Writer()
        writer.Transfer(shape, STEPControl_AsIs)
        target = os.path.join(out_dir, name)
        tmp = target + ".tmp"
        if writer.Write(tmp) != IFSelect_RetDone:
            raise SystemExit(f"{target}: OCCT could not write it")
        os.replace(tmp, target)
        print(f"{target}: {total} faces")


if __name__ == "__main__":
    main()
