#!/usr/bin/env python3
"""Absorbed power per organ and per triangle of a canopy, against a reference.

    python3 benches/canopy_absorbed.py SCENE.hir FLAT.obj REFERENCE.csv RESULTS.csv [BAND]

SCENE.hir gives the materials (rho, back_rho, tau per band); FLAT.obj (`hirad flatten
SCENE.hir -o FLAT.obj`) the material of every polygon in global-id order; the CSVs are
`hirad solve --results` tables. Absorbed power of a polygon is area x (1 - rho - tau) x
irradiance, summed over its receiving sides. Prints, per material, the total absorbed power's
relative error, and over all triangles (those absorbing at least 1e-6 of the largest) the
median and 90th percentile of the per-triangle relative error.
"""
import csv
import sys


def materials(path):
    out = {}
    for line in open(path):
        t = line.split()
        if not t or t[0] != 'material':
            continue
        name, rest, m = t[1], t[2:], {}
        key = None
        for w in rest:
            try:
                m.setdefault(key, []).append(float(w))
            except ValueError:
                key = w
        out[name] = m
    return out


def absorbed(path, mats, kinds, band):
    rows = list(csv.DictReader(open(path)))
    out = []
    for i, row in enumerate(rows):
        m = mats[kinds[i]]
        rho = m.get('rho', [0] * 8)[band]
        tau = m.get('tau', [0] * 8)[band]
        a = float(row['area']) * (1 - rho - tau) * float(row['irr_%d' % band])
        if 'back_rho' in m or 'tau' in m:
            back = m.get('back_rho', m.get('rho'))[band]
            a += float(row['area']) * (1 - back - tau) * float(row['irr_back_%d' % band])
        out.append(a)
    return out


def main():
    scene, flat, ref, res = sys.argv[1:5]
    band = int(sys.argv[5]) if len(sys.argv) > 5 else 0
    mats = materials(scene)
    kinds, cur = [], None
    for line in open(flat):
        if line.startswith('usemtl'):
            cur = line.split()[1]
        elif line.startswith('f '):
            kinds.append(cur)
    r = absorbed(ref, mats, kinds, band)
    g = absorbed(res, mats, kinds, band)
    per = {}
    for k, x, y in zip(kinds, r, g):
        t = per.setdefault(k, [0.0, 0.0])
        t[0] += x
        t[1] += y
    top = max(r)
    rel = sorted(abs(y / x - 1) for x, y in zip(r, g) if x > 1e-6 * top)
    n = len(rel)
    print(' '.join('%s %+.2f%%' % (k, 100 * (v[1] / v[0] - 1)) for k, v in sorted(per.items())),
          '| per triangle: median %.1f%% p90 %.1f%% (%d triangles)'
          % (100 * rel[n // 2], 100 * rel[int(0.9 * n)], n))


if __name__ == '__main__':
    main()
