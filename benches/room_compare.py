#!/usr/bin/env python3
"""room_compare.py HR.csv HI.csv: per material, absorbed power (green band) and per-polygon
irradiance error (front + back) of polygons above 1% of their material's largest; then the
furniture (groups outside scene/room) and the room apart."""
import sys, numpy as np, csv
def load(p):
    with open(p) as f:
        r = csv.reader(f); h = next(r); rows = list(r)
    col = {n: i for i, n in enumerate(h)}
    def num(name):
        i = col[name]
        return np.array([float(x[i]) if x[i] else 0.0 for x in rows])
    area = num('area_m2')
    irr = num('irr_green_W_m2') + num('irr_back_green_W_m2')
    ab = area * (irr - num('rad_green_W_m2') - num('rad_back_green_W_m2'))
    mat = np.array([x[col['material']] for x in rows])
    grp = np.array([x[col['group']] for x in rows])
    return irr, ab, mat, grp, area
a_irr, a_ab, mat, grp, area = load(sys.argv[1])
b_irr, b_ab, _, _, _ = load(sys.argv[2])
inst = np.array(['room' not in g for g in grp])
print(f"{'material':12} {'n':>6} {'tot hr W':>10} {'tot':>7} {'signed med':>10} {'abs med':>8} {'p90':>7} {'worst':>7}")
allE = []
for m in sorted(set(mat)):
    k = (mat == m)
    big = k & (a_irr > 0.01 * a_irr[k].max())
    if big.sum() == 0: continue
    e = (b_irr[big] / a_irr[big] - 1) * 100
    allE.append(e)
    print(f"{m:12} {k.sum():6d} {a_ab[k].sum():10.2f} {100*(b_ab[k].sum()/a_ab[k].sum()-1):+6.1f}% {np.median(e):+9.1f}% {np.median(abs(e)):7.1f}% {np.percentile(abs(e),90):6.1f}% {abs(e).max():6.0f}%")
for name, k in [('furniture', inst), ('room', ~inst)]:
    big = k & (a_irr > 1e-3 * a_irr.max())
    e = (b_irr[big] / a_irr[big] - 1) * 100
    print(f"{name}: n {big.sum()} signed median {np.median(e):+.1f}% abs median {np.median(abs(e)):.1f}% p90 {np.percentile(abs(e),90):.1f}%")
