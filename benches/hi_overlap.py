"""Closed siblings whose boxes overlap: hi against hr on a grid of one tree original.

Builds a scene of an N x N grid of one original of `hirad gen forest --trees 1` (by default
branch2-0, a poplar branch of 2,609 polygons) on a soil square, bakes its tables, solves it
with hr and with hi (`--instancing every:3`: the grid's instances closed, their contents
expanded when opened), and prints the light absorbed per material class (W) and the power
balance, then the near-infrared irradiance by height. The spacing sets how far the
instances' boxes overlap (0.5 m: most of their volume; 1.5 m: little).

    python3 benches/hi_overlap.py --hirad target/release/hirad --spacing 0.5 --work /tmp/ov

Shares no code with the solver: the absorption is computed here from the results table and
the materials' coefficients.
"""

import argparse
import collections
import csv
import json
import math
import os
import random
import subprocess


def run(cmd, may_fail=False):
    """Runs `cmd`; a failure stops the script with its error, unless `may_fail` (a bake
    that misses its error targets exits 1 with its tables written)."""
    r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0 and not may_fail:
        raise SystemExit(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stderr[-2000:]}")


def originals(text):
    """The header (up to the first original) and each original's lines, by name."""
    lines = text.split("\n")
    head, blocks, name = [], {}, None
    for line in lines:
        if line.startswith("original "):
            name = line.split()[1]
            blocks[name] = []
        elif line.startswith("scene "):
            name = "\0scene"
            blocks[name] = []
        if name is None:
            head.append(line)
        else:
            blocks[name].append(line)
    return head, blocks


def needed(blocks, root):
    """`root` and the originals its instances name, children first."""
    order, seen = [], set()

    def visit(n):
        if n in seen:
            return
        seen.add(n)
        for line in blocks[n]:
            w = line.split()
            if w and w[0] == "instance":
                visit(w[1])
        order.append(n)

    visit(root)
    return order


def scene(head, blocks, root, n, spacing, ground, z, cells=8):
    out = [line for line in head if not line.startswith("camera")]
    for name in needed(blocks, root):
        out += blocks[name]
    out.append("scene grid {")
    out.append("  cluster ground {")
    for i in range(cells):
        for j in range(cells):
            x0 = -ground + 2 * ground * i / cells
            x1 = -ground + 2 * ground * (i + 1) / cells
            y0 = -ground + 2 * ground * j / cells
            y1 = -ground + 2 * ground * (j + 1) / cells
            out += [f"    v {x0} {y0} 0", f"    v {x1} {y0} 0", f"    v {x1} {y1} 0", f"    v {x0} {y1} 0"]
    for k in range(cells * cells):
        out.append(f"    quad soil {4 * k} {4 * k + 1} {4 * k + 2} {4 * k + 3}")
    out.append("  }")
    out.append("  cluster trees {")
    rng = random.Random(1)
    for i in range(n):
        for j in range(n):
            a = rng.uniform(0, 2 * math.pi)
            x, y = (i - (n - 1) / 2) * spacing, (j - (n - 1) / 2) * spacing
            out.append(
                f"    instance {root} exact translate {x} {y} {z} quat {math.cos(a / 2)} 0 0 {math.sin(a / 2)}"
            )
    out += ["  }", "}", ""]
    return "\n".join(out)


def materials(text):
    m = {}
    for line in text.split("\n"):
        w = line.split()
        if w and w[0] == "material":
            d, k = {}, None
            for t in w[2:]:
                try:
                    d.setdefault(k, []).append(float(t))
                except ValueError:
                    k = t
            m[w[1]] = d
    return m


def absorbed(path, mats):
    """Absorbed power (W) per material and band, both sides."""
    tot = collections.defaultdict(lambda: [0.0, 0.0])
    for r in csv.DictReader(open(path)):
        d = mats[r["material"]]
        a = float(r["area_m2"])
        for b, band in enumerate(["par", "nir"]):
            rho = d.get("rho", [0, 0])[b]
            back = d.get("back_rho", d.get("rho", [0, 0]))[b]
            tau = d.get("tau", [0, 0])[b]
            front = float(r[f"irr_{band}_W_m2"] or 0)
            rear = float(r[f"irr_back_{band}_W_m2"] or 0)
            tot[r["material"]][b] += a * (front * (1 - rho - tau) + rear * (1 - back - tau))
    return tot


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--hirad", default="target/release/hirad")
    ap.add_argument("--original", default="branch2-0")
    ap.add_argument("--n", type=int, default=3)
    ap.add_argument("--spacing", type=float, default=0.5)
    ap.add_argument("--z", type=float, default=0.05, help="height of the instances' origin over the soil (m)")
    ap.add_argument("--work", default="hi_overlap")
    ap.add_argument("--tables", default="--max-single-side 0 --max-out-side 16 --max-side 16 --tau-target 0.02 --epsilon 1e-3")
    ap.add_argument("--hi", default="--instancing every:3", help="extra arguments of the hi solve")
    ap.add_argument("--hr", default="", help="extra arguments of the hr solve")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    w = lambda f: os.path.join(a.work, f)
    run([a.hirad, "gen", "forest", "--trees", "1", "-o", w("forest1.hir")])
    text = open(w("forest1.hir")).read()
    head, blocks = originals(text)
    ground = max(2.0, a.spacing * a.n)
    open(w("grid.hir"), "w").write(scene(head, blocks, a.original, a.n, a.spacing, ground, a.z))
    run([a.hirad, "tables", w("grid.hir"), "-o", w("grid.hirb")] + a.tables.split(), may_fail=True)
    if not os.path.exists(w("grid.hirb")):
        raise SystemExit("the tables were not written")
    for method, extra in [("hr", a.hr.split()), ("hi", a.hi.split())]:
        # Exit 1 (a balance beyond 5%) still writes the outputs this compares.
        run([a.hirad, "solve", w("grid.hirb"), "--method", method, "-q", "--results", w(f"{method}.csv"),
             "--stats", w(f"{method}.json")] + extra, may_fail=True)
    mats = materials(text)
    hr, hi = absorbed(w("hr.csv"), mats), absorbed(w("hi.csv"), mats)
    print(f"{a.n} x {a.n} {a.original}, {a.spacing} m apart; absorbed (W), hi against hr")
    for m in sorted(hr):
        cells = []
        for b, band in enumerate(["PAR", "NIR"]):
            x, y = hr[m][b], hi[m][b]
            cells.append(f"{band} {x:10.2f} {y:10.2f} {100 * (y / x - 1) if x else 0:+6.2f}%")
        print(f"  {m:6s} " + "   ".join(cells))
    for method in ["hr", "hi"]:
        d = json.load(open(w(f"{method}.json")))
        print(f"  balance {method}: " + ", ".join(f"{p['band']} {p['imbalance_percent']:+.2f}%" for p in d["power"]))


if __name__ == "__main__":
    main()
