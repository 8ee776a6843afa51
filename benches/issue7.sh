#!/usr/bin/env bash
# hr right per polygon (issue 7): before and after in one run, both binaries interleaved.
#   OLD=/path/to/hirad-built-from-6e9e1db [NEW_ARGS="--final-rays 0"] bash benches/issue7.sh
# NEW_ARGS: extra options for the new build only (word-split).
# References and scenes go to $WORK (default /tmp/hirad-issue7); the exact references take
# about two minutes the first time. Prints one line per measurement (BENCHMARKS.md).
set -u
cd "$(dirname "$0")/.."
NEW=${NEW:-target/release/hirad}
OLD=${OLD:?set OLD to a release build of 6e9e1db}
CB=fixtures/obj/cornell_triangles.obj
W=${WORK:-/tmp/hirad-issue7}
mkdir -p "$W"
[ -f "$W/cornell_exact.csv" ] || "$NEW" solve "$CB" --method exact --elements 8000 --results "$W/cornell_exact.csv" -q
[ -f "$W/leaves_exact.csv" ] || "$NEW" solve fixtures/leaves_cluster.hir --method exact --elements 8000 --results "$W/leaves_exact.csv" -q
[ -f "$W/poplar.hirb" ] || "$NEW" gen poplar --preset paper -q -o "$W/poplar.hirb"
if [ ! -f "$W/stack10000.hir" ]; then
  {
    printf 'hirad 1\nbands 1\nmaterial grey rho 0.5\nmaterial lamp rho 0 emit 1\nscene {\n'
    printf '  quad lamp -0.5 -0.5 1  -0.5 0.5 1  0.5 0.5 1  0.5 -0.5 1\n  cluster stack {\n'
    for _ in $(seq 10000); do printf '    tri grey 0 0 0  0.000001 0 0  0 0.000001 0\n'; done
    printf '  }\n}\n'
  } > "$W/stack10000.hir"
fi
echo "load: $(cat /proc/loadavg)"
for e in 1e-3 1e-4 1e-5; do
  for b in OLD NEW; do
    H=${!b}
    /usr/bin/time -f "%e %M" -o "$W/time.txt" "$H" solve $([ "$b" = NEW ] && echo "${NEW_ARGS:-}") "$CB" --epsilon $e --results "$W/cb_$b.csv" -q --stats "$W/cb_$b.json" 2>/dev/null
    links=$(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['links'])" "$W/cb_$b.json")
    r=$(python3 benches/compare.py "$W/cornell_exact.csv" "$W/cb_$b.csv" --skip 10,11 | head -2 | tr '\n' ' ')
    echo "cornell_triangles eps $e $b seconds,rss_kb $(cat "$W/time.txt") links $links | $r"
  done
done
for b in OLD NEW; do
  H=${!b}
  /usr/bin/time -f "%e %M" -o "$W/time.txt" "$H" solve $([ "$b" = NEW ] && echo "${NEW_ARGS:-}") fixtures/leaves_cluster.hir --results "$W/lv_$b.csv" -q 2>/dev/null
  python3 -c "
import csv, sys
ex = list(csv.DictReader(open(sys.argv[1]))); hr = list(csv.DictReader(open(sys.argv[2])))
n = len(ex)
errs = [100 * (float(hr[i][c]) / float(ex[i][[k for k in ex[0] if k.startswith('rad_')][[k for k in hr[0] if k.startswith('rad_')].index(c)]]) - 1) for i in range(n - 12, n)
        for c in [k for k in hr[0] if k.startswith('rad_')]]
print('leaves_cluster', sys.argv[3], 'seconds,rss_kb', sys.argv[4],
      'worst of 48 leaf sides and bands %+.1f%%' % max(errs, key=abs))
" "$W/leaves_exact.csv" "$W/lv_$b.csv" "$b" "$(cat "$W/time.txt")"
done
for b in OLD NEW; do
  H=${!b}
  # (The old build has no --max-imbalance; the new one must not fail on the balance here.)
  X=(); [ "$b" = NEW ] && X=(--max-imbalance 100)
  /usr/bin/time -f "%e %M" -o "$W/time.txt" "$H" solve $([ "$b" = NEW ] && echo "${NEW_ARGS:-}") "$W/poplar.hirb" --results "$W/pop_$b.csv" -q --stats "$W/pop_$b.json" "${X[@]}" 2>/dev/null
  echo "poplar $b seconds,rss_kb $(cat "$W/time.txt") links $(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['links'])" "$W/pop_$b.json")"
done
for b in OLD NEW; do
  H=${!b}
  /usr/bin/time -f "%e %M" -o "$W/time.txt" timeout 60 "$H" solve $([ "$b" = NEW ] && echo "${NEW_ARGS:-}") "$W/stack10000.hir" --results "$W/st_$b.csv" -q 2>/dev/null
  echo "stack10000 $b exit $? seconds,rss_kb $(tail -1 "$W/time.txt")"
done
echo "load: $(cat /proc/loadavg)"
