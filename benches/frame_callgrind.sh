#!/usr/bin/env bash
# Instructions per frame, fat borders vs off, counted by callgrind on single-threaded llvmpipe
# (LP_NUM_THREADS=0): repeatable where wall-clock frame times on a shared 2-core machine are not.
# Per frame = (count for 25 frames − count for 5 frames) / 20, so start-up and shader compilation
# cancel out (start-up varies by up to ~2e8 instructions between runs, hence the long difference).
# Takes about 15 minutes. Needs valgrind.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --example render_frames
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$(mktemp -d)}
chmod 700 "$XDG_RUNTIME_DIR"
count() {
  LP_NUM_THREADS=0 valgrind --tool=callgrind --callgrind-out-file=/dev/null \
    ./target/release/examples/render_frames "$1" "$2" "$3" 2>&1 | awk '/Collected/ {print $4}'
}
printf '%-6s %-8s %16s %8s\n' msaa variant instr/frame ratio
for msaa in 1 4; do
  base=""
  for variant in off 6 4 2; do
    a=$(count "$variant" "$msaa" 5)
    b=$(count "$variant" "$msaa" 25)
    per=$(( (b - a) / 20 ))
    [ -n "$base" ] || base=$per
    printf '%-6s %-8s %16d %8.3f\n' "$msaa" "$variant" "$per" "$(echo "$per / $base" | bc -l)"
  done
done
