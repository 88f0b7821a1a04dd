#!/usr/bin/env bash
# Seeds fuzz/corpus/<target>/ from the repository's own models and test inputs (run from the
# repository root). The corpora are not committed; crashes found are kept as regression
# inputs under tests/data/fuzz/<target>/ (replayed by tests/fuzz_regressions.rs).
set -euo pipefail
seed() { # target, files…
  local t=$1; shift
  mkdir -p "fuzz/corpus/$t"
  for f in "$@"; do
    [ -f "$f" ] && [ "$(stat -c %s "$f")" -le 200000 ] && cp "$f" "fuzz/corpus/$t/" || true
  done
}
shopt -s nullglob
seed bpt models/*.bpt tests/data/bad/*.bpt tests/data/fuzz/bpt/*
seed tessellate models/*.bpt tests/data/fuzz/tessellate/*
seed step_p21 tests/data/step/*.step tests/data/step/hostile/*.step models/screw.step tests/data/fuzz/step_p21/*
seed step tests/data/step/*.step tests/data/step/hostile/*.step models/screw.step tests/data/fuzz/step/*
seed gltf tests/data/mesh/*.gltf tests/data/mesh/*.glb tests/data/bad/*.gltf tests/data/fuzz/gltf/*
seed obj tests/data/mesh/*.obj tests/data/bad/*.obj tests/data/fuzz/obj/*
seed ply tests/data/mesh/*.ply tests/data/bad/*.ply tests/data/fuzz/ply/*
seed stl tests/data/mesh/*.stl tests/data/bad/*.stl tests/data/fuzz/stl/*
seed iges tests/data/iges/*.igs tests/data/iges/*.iges models/corpus/example_45_faces.iges tests/data/fuzz/iges/*
# trimmed: the first byte picks the reader (even STEP, odd IGES) and the tolerance.
mkdir -p fuzz/corpus/trimmed
for f in tests/data/step/*.step models/screw.step tests/data/fuzz/trimmed/*; do
  [ -f "$f" ] && [ "$(stat -c %s "$f")" -le 200000 ] || continue
  { printf '\x02'; cat "$f"; } > "fuzz/corpus/trimmed/s-$(basename "$f")"
done
for f in tests/data/iges/*.igs tests/data/iges/*.iges models/corpus/example_45_faces.iges; do
  [ -f "$f" ] && [ "$(stat -c %s "$f")" -le 200000 ] || continue
  { printf '\x03'; cat "$f"; } > "fuzz/corpus/trimmed/i-$(basename "$f")"
done
