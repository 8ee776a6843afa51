"""hi against hr by material and by depth of the polygons' group path.

Reads two results tables of the same scene (`hirad solve --results`), hr's and hi's, and
prints, per material and per depth of the `group` column (the number of parts of the path:
`scene/trees/#0/#2` is 4; in `gen forest`, 3 is a tree's own polygons, each instance level
one more), the absorbed power (W, both sides, irradiance less radiosity times area: valid
for polygons that emit nothing) and hi's median relative error of NIR irradiance.

    python3 benches/hi_by_depth.py hr.csv hi.csv

Shares no code with the solver.
"""

import collections
import csv
import sys


def load(path):
    out = {}
    with open(path) as f:
        r = csv.reader(f)
        next(r)
        for row in r:
            a = float(row[1])

            def g(i):
                return float(row[i]) if row[i] else 0.0

            par = a * (g(4) + g(8) - g(2) - g(6))
            nir = a * (g(5) + g(9) - g(3) - g(7))
            out[int(row[0])] = (row[10], row[11].count("/") + 1, par, nir, a * (g(5) + g(9)))
    return out


def main():
    hr, hi = load(sys.argv[1]), load(sys.argv[2])
    agg = collections.defaultdict(lambda: [0.0, 0.0, 0.0, 0.0, 0])
    rel = collections.defaultdict(list)
    for k, (m, d, p, n, irr) in hr.items():
        q = hi[k]
        a = agg[(m, d)]
        a[0] += p
        a[1] += q[2]
        a[2] += n
        a[3] += q[3]
        a[4] += 1
        if irr > 0:
            rel[(m, d)].append((q[4] - irr) / irr)
    pct = lambda x, y: 100 * (y / x - 1) if x else 0.0
    print("material depth polygons  PAR hr (W) hi/hr  NIR hr (W) hi/hr  NIR irradiance median")
    tot = collections.defaultdict(lambda: [0.0] * 4)
    for key in sorted(agg):
        a = agg[key]
        r = sorted(rel[key])
        med = r[len(r) // 2] if r else 0.0
        print(f"{key[0]:8s} {key[1]:5d} {a[4]:9d} {a[0]:10.1f} {pct(a[0], a[1]):+6.2f}% "
              f"{a[2]:10.1f} {pct(a[2], a[3]):+6.2f}% {100 * med:+6.2f}%")
        for i in range(4):
            tot[key[0]][i] += a[i]
    for m, t in sorted(tot.items()):
        print(f"{m:8s}   all PAR {pct(t[0], t[1]):+6.2f}%  NIR {t[2]:.1f} -> {t[3]:.1f} {pct(t[2], t[3]):+6.2f}%")


if __name__ == "__main__":
    main()
