#!/usr/bin/env bash
# hr faster at equal accuracy (issue 8): error against time on one thread on the Cornell box
# as 32 triangles, before and after, both builds interleaved in one run; then the paper
# poplar with its defaults on 1 and 2 threads.
#   OLD=/path/to/hirad-built-from-3737cfe bash benches/issue8.sh
# Each configuration runs RUNS times (default 5); the line gives the median and the fastest
# of the run's own `seconds` (reading the scene to writing the report), the walls-only L2
# against the exact reference (lamp left out: faces 10 and 11; % of the largest radiosity)
# and the links. The exact reference (`--method exact --elements 8000`, about a minute) and
# the poplar go to $WORK (default /tmp/hirad-issue8). Set POPLAR=0 to skip the poplar.
set -u
cd "$(dirname "$0")/.."
NEW=${NEW:-target/release/hirad}
OLD=${OLD:?set OLD to a release build of 3737cfe}
RUNS=${RUNS:-5}
W=${WORK:-/tmp/hirad-issue8}
CB=fixtures/obj/cornell_triangles.obj
mkdir -p "$W"
[ -f "$W/cornell_exact.csv" ] || "$NEW" solve "$CB" --method exact --elements 8000 --results "$W/cornell_exact.csv" -q
echo "load: $(cat /proc/loadavg)"
median() { python3 -c "import sys; v = sorted(map(float, sys.argv[1:])); print('%.4f %.4f' % (v[len(v) // 2], v[0]))" "$@"; }
seconds() { python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['seconds'])" "$1"; }
links() { python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['links'])" "$1"; }
cornell() { # label binary epsilon extra-arguments...
  local label=$1 bin=$2 eps=$3
  shift 3
  local ts=()
  for _ in $(seq "$RUNS"); do
    "$bin" solve "$CB" --threads 1 --epsilon "$eps" "$@" --results "$W/cb.csv" --stats "$W/s.json" -q --max-imbalance 100 2>/dev/null
    ts+=("$(seconds "$W/s.json")")
  done
  local l2
  l2=$(python3 benches/compare.py "$W/cornell_exact.csv" "$W/cb.csv" --skip 10,11 | head -1 | cut -d' ' -f2)
  echo "cornell $label eps $eps [$*] median,fastest s $(median "${ts[@]}") | walls L2 $l2 % | links $(links "$W/s.json")"
}
for eps in 1e-2 3e-3 1e-3 5e-4 3.5e-4 3e-4 1e-4 3e-5 1e-5; do
  for b in OLD NEW; do
    cornell "$b" "${!b}" "$eps" --final-rays 0
  done
done
for eps in 1e-3 3e-4 1e-4; do
  for b in OLD NEW; do
    cornell "$b" "${!b}" "$eps"
  done
done
if [ "${POPLAR:-1}" != 0 ]; then
  [ -f "$W/poplar.hirb" ] || "$NEW" gen poplar --preset paper -q -o "$W/poplar.hirb"
  for t in 1 2; do
    for b in OLD NEW; do
      /usr/bin/time -f "%e s wall, %U s user, %M KB" -o "$W/time.txt" "${!b}" solve "$W/poplar.hirb" --threads $t --stats "$W/p.json" -q --max-imbalance 100 2>/dev/null
      echo "poplar $b threads $t: $(cat "$W/time.txt"), $(python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
print('links', d['links'], 'iterations', d['iterations'], 'imbalance %', ' '.join('%+.2f' % p['imbalance_percent'] for p in d['power']))
print('   phases', ', '.join('%s %.2f' % (p['phase'], p['seconds']) for p in d['phases']))" "$W/p.json")"
    done
  done
fi
echo "load: $(cat /proc/loadavg)"
