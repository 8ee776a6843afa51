#!/usr/bin/env bash
# Runs every fuzz target for SECONDS seconds (default 60), seeded from fixtures/.
# Usage: fuzz/run.sh [SECONDS [TARGET...]] (targets: binary_view text_parse obj_import
# results_read c_api c_solve; all by default). Needs cargo-fuzz (`cargo install cargo-fuzz --locked`).
# Prints each target's execution count; exits non-zero on the first finding (the crashing
# input is left in fuzz/artifacts/TARGET/).
set -euo pipefail
SECONDS_PER_TARGET="${1:-60}"
shift || true
TARGETS=("$@")
[ "${#TARGETS[@]}" -gt 0 ] || TARGETS=(binary_view text_parse obj_import results_read c_api c_solve)
cd "$(dirname "$0")"
ROOT="$(cd .. && pwd)"

seed() {
  local target="$1"
  mkdir -p "corpus/$target"
  case "$target" in
    text_parse)
      cp "$ROOT"/fixtures/*.hir "corpus/$target/" 2>/dev/null || true ;;
    obj_import)
      for f in "$ROOT"/fixtures/obj/*.obj; do
        [ -e "$f" ] || continue
        local base="${f%.obj}"
        # OBJ, a 0xFF separator, then the first MTL the OBJ names (if any).
        local mtl
        mtl="$(grep -m1 '^mtllib' "$f" | awk '{print $2}' | tr -d '\r' || true)"
        { cat "$f"; if [ -n "$mtl" ] && [ -e "$(dirname "$f")/$mtl" ]; then printf '\xff'; cat "$(dirname "$f")/$mtl"; fi; } \
          > "corpus/$target/$(basename "$base").seed"
      done ;;
    results_read)
      (cd "$ROOT" && cargo build --release -q -p hirad)
      for f in "$ROOT"/fixtures/*.hir; do
        "$ROOT/target/release/hirad" solve -q "$f" --epsilon 1e-2 --results "corpus/$target/$(basename "${f%.hir}").csv" || true
      done ;;
    c_api)
      # A mode byte (0: from memory, 1: through a reader), then an image.
      (cd "$ROOT" && cargo build --release -q -p hirad)
      for f in "$ROOT"/fixtures/*.hir; do
        local image
        image="$(mktemp)"
        "$ROOT/target/release/hirad" convert -q "$f" -o "$image.hirb"
        for mode in 0 1; do
          { printf "\\x0$mode"; cat "$image.hirb"; } > "corpus/$target/$(basename "${f%.hir}")_$mode.seed"
        done
        rm -f "$image" "$image.hirb"
      done ;;
    c_solve)
      # Bytes that pick a fixture, settings, a workspace and callbacks: all zeros (the
      # defaults on the first fixture), and a few of every byte value.
      head -c 64 /dev/zero > "corpus/$target/defaults.seed"
      for v in 1 2 3 85 170 255; do
        printf "$(printf '\\x%02x' "$v")%.0s" $(seq 64) > "corpus/$target/bytes_$v.seed"
      done ;;
    binary_view)
      (cd "$ROOT" && cargo build --release -q -p hirad)
      for f in "$ROOT"/fixtures/*.hir; do
        "$ROOT/target/release/hirad" convert -q "$f" -o "corpus/$target/$(basename "${f%.hir}").hirb"
      done
      # An image with directional tables (small grids, so that it stays under -max_len; the
      # targets are not met, which exits 1 after writing it).
      "$ROOT/target/release/hirad" tables -q "$ROOT/fixtures/small_plant.hir" --max-side 4 \
        --max-tau-side 4 --max-out-side 8 --max-single-side 4 --tau-target 1 \
        -o "corpus/$target/small_plant_tables.hirb" >/dev/null 2>&1 || true ;;
  esac
}

for target in "${TARGETS[@]}"; do
  seed "$target"
  echo "== fuzzing $target for ${SECONDS_PER_TARGET}s"
  log="$(mktemp)"
  status=0
  cargo fuzz run -s none "$target" "corpus/$target" -- \
      -max_total_time="$SECONDS_PER_TARGET" -max_len=65536 -timeout=10 -rss_limit_mb=4096 \
      >"$log" 2>&1 || status=$?
  execs="$(grep -Eo 'Done [0-9]+ runs' "$log" | tail -1 || true)"
  echo "== $target: ${execs:-no summary} (exit $status)"
  if [ "$status" -ne 0 ]; then
    tail -60 "$log"
    exit "$status"
  fi
  rm -f "$log"
done
