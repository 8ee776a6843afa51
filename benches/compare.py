#!/usr/bin/env python3
"""Per-polygon comparison of two hirad results tables (CSV): the L2 error (area-weighted, in
percent of the reference's largest radiosity) and the worst relative errors, optionally
leaving out polygons (e.g. the lamp, whose radiosity would set the scale).

    python3 benches/compare.py REFERENCE.csv RESULT.csv [--skip 10,11] [--ids 0-5,12]

Used by BENCHMARKS.md; standard library only."""
import csv, math, sys

def ranges(text):
    out = set()
    for part in filter(None, text.split(',')):
        a, _, b = part.partition('-')
        out.update(range(int(a), int(b or a) + 1))
    return out

def main():
    args = sys.argv[1:]
    ref, got = list(csv.DictReader(open(args[0]))), list(csv.DictReader(open(args[1])))
    skip = ranges(args[args.index('--skip') + 1]) if '--skip' in args else set()
    only = ranges(args[args.index('--ids') + 1]) if '--ids' in args else None
    cols = [c for c in ref[0] if c.startswith('rad')]
    num = den = top = 0.0
    worst = []
    for a, b in zip(ref, got):
        i = int(a['id'])
        if i in skip or (only is not None and i not in only):
            continue
        area = float(a['area_m2'] if 'area_m2' in a else a['area'])
        for c in cols:
            r, g = float(a[c]), float(b[c])
            top = max(top, r)
            num += area * (g - r) ** 2
            den += area
            if r > 0:
                worst.append((abs(g - r) / r, i, c, r, g))
    worst.sort(reverse=True)
    print('L2 %.4f %% of the largest radiosity %.6g over %d columns' % (100 * math.sqrt(num / den) / top, top, len(worst)))
    for e, i, c, r, g in worst[:5]:
        print('  id %d %s: reference %.5g, got %.5g, %+.2f %%' % (i, c, r, g, 100 * (g - r) / r))

if __name__ == '__main__':
    main()
