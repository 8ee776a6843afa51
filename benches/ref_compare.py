#!/usr/bin/env python3
"""Per-polygon error of solve results against `mc_reference.py`'s sample of polygons.

    python3 benches/ref_compare.py ref.csv hr.csv hi.csv ...

For every results table, per band and side: relative error of each sampled polygon's
irradiance (median, 90th percentile), the L2 error as % of the largest reference value,
and the power-weighted total; the worst polygon (its id, and its reference value against the result); the reference's
own standard error (median, relative) is printed first, so that what the reference
cannot resolve is seen.
"""

import csv
import sys


def load(path):
    with open(path) as f:
        r = csv.reader(f)
        head = next(r)
        return head, {int(row[0]): row for row in r}


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * len(xs)))] if xs else float("nan")


def main():
    rh, ref = load(sys.argv[1])
    cols = [c for c in rh if c.startswith("irr_")]
    for c in cols:
        se = rh.index(c.replace("irr_", "se_"))
        i = rh.index(c)
        noise = [float(row[se]) / float(row[i]) for row in ref.values() if row[i] and float(row[i]) > 0]
        print(f"{c}: reference {len(noise)} polygons, its standard error median {100 * pct(noise, 0.5):.2f}% p90 {100 * pct(noise, 0.9):.2f}%")
    for path in sys.argv[2:]:
        h, res = load(path)
        print(path)
        for c in cols:
            i, j, ai = rh.index(c), h.index(c), h.index("area_m2")
            errs, sq, top, p_ref, p_res = [], 0.0, 0.0, 0.0, 0.0
            worst = (0.0, None, 0.0, 0.0)
            for k, row in ref.items():
                if not row[i] or k not in res or not res[k][j]:
                    continue
                u, v = float(row[i]), float(res[k][j])
                a = float(res[k][ai])
                top = max(top, u)
                sq += (v - u) ** 2
                p_ref += a * u
                p_res += a * v
                if u > 1e-3:
                    errs.append(abs(v / u - 1))
                    if errs[-1] > worst[0]:
                        worst = (errs[-1], k, u, v)
            n = len(errs)
            l2 = 100 * (sq / max(n, 1)) ** 0.5 / top if top > 0 else float("nan")
            print(f"  {c:22s} n {n:6d} median {100 * pct(errs, 0.5):6.2f}% p90 {100 * pct(errs, 0.9):6.2f}% L2 {l2:5.2f}% of max, power {100 * (p_res / p_ref - 1):+.2f}%, worst {100 * worst[0]:.0f}% (polygon {worst[1]}: {worst[2]:.4g} -> {worst[3]:.4g})")


if __name__ == "__main__":
    main()
