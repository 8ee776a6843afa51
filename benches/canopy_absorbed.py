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


def column(fields, quantity, band):
    """The band-th column of `quantity` ('irr', 'irr_back', ...): tables name bands by index
    (`irr_0`) or by name with units (`irr_par_W_m2`), in band order either way."""
    cols = [c for c in fields if c.startswith(quantity + '_')
            and (quantity.endswith('_back') or not c.startswith(quantity + '_back_'))]
    return cols[band]


def absorbed(path, mats, kinds, band):
    reader = csv.DictReader(open(path))
    rows = list(reader)
    area = 'area_m2' if 'area_m2' in reader.fieldnames else 'area'
    front, back_col = column(reader.fieldnames, 'irr', band), None
    out = []
    for i, row in enumerate(rows):
        m = mats[kinds[i]]
        rho = m.get('rho', [0] * 8)[band]
        tau = m.get('tau', [0] * 8)[band]
        a = float(row[area]) * (1 - rho - tau) * float(row[front])
        if 'back_rho' in m or 'tau' in m:
            back = m.get('back_rho', m.get('rho'))[band]
            back_col = back_col or column(reader.fieldnames, 'irr_back', band)
            a += float(row[area]) * (1 - back - tau) * float(row[back_col] or 0)
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
