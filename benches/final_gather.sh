#!/usr/bin/env bash
# The final gather (issue 7): the same build with `--final-rays 0` (the hierarchy alone) and
# with its defaults, interleaved in one run. References (`--method exact`) and scenes go to
# $WORK (default /tmp/hirad-final-gather); the references take about three minutes the first
# time. Prints one line per measurement (BENCHMARKS.md).
#   bash benches/final_gather.sh
set -u
cd "$(dirname "$0")/.."
H=${HIRAD:-target/release/hirad}
W=${WORK:-/tmp/hirad-final-gather}
mkdir -p "$W"
CB=fixtures/obj/cornell_triangles.obj
MZ=fixtures/maize_2x2.hir
[ -f "$W/cornell_exact.csv" ] || "$H" solve "$CB" --method exact --elements 8000 --results "$W/cornell_exact.csv" -q
[ -f "$W/maize_exact.csv" ] || "$H" solve "$MZ" --method exact --results "$W/maize_exact.csv" -q --max-imbalance 100
[ -f "$W/leaves_exact.csv" ] || "$H" solve fixtures/leaves_cluster.hir --method exact --elements 8000 --results "$W/leaves_exact.csv" -q
[ -f "$W/maize.obj" ] || "$H" flatten "$MZ" -o "$W/maize.obj" -q
[ -f "$W/poplar.hirb" ] || "$H" gen poplar --preset paper -q -o "$W/poplar.hirb"
echo "load: $(cat /proc/loadavg)"
run() { # name, then solve arguments; prints seconds and peak RSS
  /usr/bin/time -f "%e s, %M KB" -o "$W/time.txt" "$H" solve "$@" -q --max-imbalance 100 --stats "$W/s.json" 2>/dev/null
  echo "$(cat "$W/time.txt"), imbalance % $(python3 -c "import json, sys; print(' '.join('%+.2f' % p['imbalance_percent'] for p in json.load(open(sys.argv[1]))['power']))" "$W/s.json")"
}
for e in 1e-3 1e-4 1e-5; do
  for g in "--final-rays 0" ""; do
    t=$(run "$CB" --epsilon $e $g --results "$W/cb.csv")
    r=$(python3 benches/compare.py "$W/cornell_exact.csv" "$W/cb.csv" --skip 10,11 2>/dev/null | head -2 | tr '\n' ' ')
    echo "cornell_triangles eps $e [${g:-defaults}] $t | $r"
  done
done
for g in "--final-rays 0" ""; do
  t=$(run "$MZ" $g --results "$W/mz.csv")
  echo "maize_2x2 [${g:-defaults}] $t | NIR: $(python3 benches/canopy_absorbed.py "$MZ" "$W/maize.obj" "$W/maize_exact.csv" "$W/mz.csv" 1)"
  echo "maize_2x2 [${g:-defaults}] PAR: $(python3 benches/canopy_absorbed.py "$MZ" "$W/maize.obj" "$W/maize_exact.csv" "$W/mz.csv" 0)"
done
for g in "--final-rays 0" ""; do
  t=$(run fixtures/leaves_cluster.hir $g --results "$W/lv.csv")
  w=$(python3 -c "
import csv, sys
ex = list(csv.DictReader(open(sys.argv[1]))); hr = list(csv.DictReader(open(sys.argv[2])))
n = len(ex)
print('worst of 48 leaf sides and bands %+.1f%%' % max((100 * (float(hr[i][c]) / float(ex[i][[k for k in ex[0] if k.startswith('rad_')][[k for k in hr[0] if k.startswith('rad_')].index(c)]]) - 1) for i in range(n - 12, n) for c in [k for k in hr[0] if k.startswith('rad_')]), key=abs))
" "$W/leaves_exact.csv" "$W/lv.csv")
  echo "leaves_cluster [${g:-defaults}] $t | $w"
done
for g in "--final-rays 0" ""; do
  echo "poplar [${g:-defaults}] $(run "$W/poplar.hirb" $g)"
done
echo "load: $(cat /proc/loadavg)"
