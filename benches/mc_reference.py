#!/usr/bin/env python3
"""Independent per-polygon reference: Monte Carlo path tracing of a sample of polygons.

Shares no code with the solver it checks: rays by Embree (pip install embreex numpy), its
own sampler (numpy), the scene as `hirad flatten --up y` writes it (faces in global-id
order, no rotation) and the lights and materials from the scene's text (`hirad convert
SCENE -o SCENE.hir`). Suns and sky directions are distant directional sources (irradiance
on a plane facing them, W/m^2); a path that escapes brings nothing.

For each chosen polygon and receiving side (the back too for a two-sided material), points
uniform over the polygon; at each, the irradiance is the direct light of the suns and of
one sky direction drawn by its share, plus the radiosity met by a cosine-distributed ray,
itself estimated by a path: at each hit, reflection or transmission by their weights,
direct light again, Russian roulette. Writes one row per polygon: id, area and, per band
and side, the mean irradiance (W/m^2) and its standard error.

    hirad convert poplar.hirb -o poplar.hir
    hirad flatten poplar.hirb --up y -o flat.obj
    python3 benches/mc_reference.py poplar.hir flat.obj ref.csv --polygons 2000 --samples 4096
"""

import argparse
import csv
import os
import sys

import numpy as np
from embreex import rtcore_scene as rtcs
from embreex.mesh_construction import TriangleMesh


def read_lights(path):
    """Bands, materials (name -> dict of arrays) and sources [(towards, irradiance)]."""
    bands, materials, sources = None, {}, []
    with open(path) as f:
        for line in f:
            w = line.split()
            if not w:
                continue
            if w[0] == "bands":
                bands = w[1:]
            elif w[0] == "material":
                nb = len(bands)
                m = {"rho": np.zeros(nb), "back_rho": None, "tau": np.zeros(nb), "emit": np.zeros(nb)}
                i = 2
                while i < len(w):
                    key = w[i]
                    vals = np.array([float(x) for x in w[i + 1 : i + 1 + nb]])
                    m[key] = vals
                    i += 1 + nb
                m["two_sided"] = m["back_rho"] is not None or np.any(m["tau"] > 0)
                if m["back_rho"] is None:
                    m["back_rho"] = m["rho"] if m["two_sided"] else np.zeros(nb)
                if np.any(m["emit"] > 0):
                    sys.exit(f"{path}: emitting materials are not supported here")
                materials[w[1]] = m
            elif w[0] in ("sun", "sky"):
                assert w[1] == "from" and w[5] == "irradiance", line
                d = np.array([float(x) for x in w[2:5]])
                irr = np.array([float(x) for x in w[6 : 6 + len(bands)]])
                sources.append((d / np.linalg.norm(d), irr, w[0]))
    return bands, materials, sources


def read_obj(path, materials):
    verts, faces, mats = [], [], []
    current = None
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("usemtl"):
                current = line.split()[1]
            elif line.startswith("f "):
                idx = [int(t.split("/")[0]) - 1 for t in line.split()[1:]]
                faces.append(idx)
                mats.append(current)
    names = sorted(materials)
    return np.array(verts, dtype=np.float64), faces, [names.index(m) for m in mats], names


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("hir")
    ap.add_argument("obj")
    ap.add_argument("out")
    ap.add_argument("--polygons", type=int, default=2000)
    ap.add_argument("--samples", type=int, default=4096, help="paths per polygon side")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--batch", type=int, default=1 << 20)
    a = ap.parse_args()
    bands, materials, sources = read_lights(a.hir)
    nb = len(bands)
    V, faces, fmat, names = read_obj(a.obj, materials)
    mat = [materials[n] for n in names]
    rho_f = np.array([m["rho"] for m in mat])
    rho_b = np.array([m["back_rho"] for m in mat])
    tau = np.array([m["tau"] for m in mat])
    two = np.array([m["two_sided"] for m in mat])
    fmat = np.array(fmat)
    # Fan triangles, each with its polygon.
    tris, owner = [], []
    for k, f in enumerate(faces):
        for j in range(1, len(f) - 1):
            tris.append([f[0], f[j], f[j + 1]])
            owner.append(k)
    tris = np.array(tris)
    owner = np.array(owner)
    T = V[tris]  # (n, 3, 3)
    cr = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    tri_area = 0.5 * np.linalg.norm(cr, axis=1)
    # Polygon normals as hirad takes them: (c1 - c0) x (c_last - c0).
    pn = np.array([np.cross(V[f[1]] - V[f[0]], V[f[-1]] - V[f[0]]) for f in faces])
    pn /= np.maximum(np.linalg.norm(pn, axis=1, keepdims=True), 1e-30)
    scene = rtcs.EmbreeScene()
    TriangleMesh(scene, T.astype(np.float32))
    size = float(np.linalg.norm(V.max(0) - V.min(0)))
    eps = 1e-6 * size
    far = 4.0 * size

    src_dir = np.array([s[0] for s in sources])
    src_irr = np.array([s[1] for s in sources])
    suns = [i for i, s in enumerate(sources) if s[2] == "sun"]
    skies = [i for i, s in enumerate(sources) if s[2] == "sky"]
    rng = np.random.default_rng(a.seed)

    def hits(o, d, tmax=None):
        """First triangle met (or -1) and its distance."""
        o32 = o.astype(np.float32)
        d32 = d.astype(np.float32)
        r = scene.run(o32, d32, output=1) if tmax is None else scene.run(o32, d32, dists=tmax, output=1)
        return r["primID"], r["tfar"]

    def open_towards(x, n, d):
        """1 where the ray from x (on the side of normal n) towards d meets nothing."""
        o = x + n * eps
        prim, _ = hits(o, d)
        return (prim < 0).astype(np.float64)

    def direct(x, n):
        """Direct irradiance (n, nb) of the suns and one sky direction drawn by share."""
        out = np.zeros((len(x), nb))
        for i in suns:
            c = n @ src_dir[i]
            lit = c > 0
            if lit.any():
                v = open_towards(x[lit], n[lit], np.broadcast_to(src_dir[i], (lit.sum(), 3)))
                out[lit] += (c[lit] * v)[:, None] * src_irr[i][None, :]
        if skies:
            sd, si = src_dir[skies], src_irr[skies]
            c = np.clip(n @ sd.T, 0.0, None)  # (n, k)
            w = c * si.mean(axis=1)[None, :]
            tot = w.sum(axis=1)
            ok = tot > 0
            if ok.any():
                cdf = np.cumsum(w[ok], axis=1) / tot[ok][:, None]
                u = rng.random(ok.sum())
                k = (u[:, None] > cdf).sum(axis=1).clip(0, len(skies) - 1)
                v = open_towards(x[ok], n[ok], sd[k])
                # Estimator of the sum over sky directions of c_k * irr_k per band.
                pk = w[ok][np.arange(ok.sum()), k] / tot[ok]
                ck = c[ok][np.arange(ok.sum()), k]
                out[ok] += (v * ck / pk)[:, None] * si[k]
        return out

    def cosine_dirs(n):
        m = len(n)
        u1, u2 = rng.random(m), rng.random(m)
        r, phi = np.sqrt(u1), 2 * np.pi * u2
        a = np.where(np.abs(n[:, 0:1]) > 0.9, np.array([[0.0, 1.0, 0.0]]), np.array([[1.0, 0.0, 0.0]]))
        t = np.cross(n, a)
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        b = np.cross(n, t)
        return (r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + np.sqrt(1 - u1)[:, None] * n

    def radiosity_along(x, n):
        """Estimates of the radiosity met by cosine rays from x on the side of n (n, nb)."""
        m = len(x)
        result = np.zeros((m, nb))
        weight = np.ones((m, nb))
        alive = np.arange(m)
        o, nn = x, n
        for _depth in range(200):
            if len(alive) == 0:
                break
            d = cosine_dirs(nn)
            prim, t = hits(o + nn * eps, d)
            hit = prim >= 0
            alive, o, d, t, prim, weight = alive[hit], o[hit], d[hit], t[hit], prim[hit], weight[hit]
            if len(alive) == 0:
                break
            y = o + d * t[:, None]
            q = owner[prim]
            mq = fmat[q]
            front = (pn[q] * d).sum(axis=1) < 0  # arriving on the front side
            ny = np.where(front[:, None], pn[q], -pn[q])  # the side met
            r_side = np.where(front[:, None], rho_f[mq], rho_b[mq])
            r_side = np.where((~front[:, None]) & (~two[mq][:, None]), 0.0, r_side)
            t_side = np.where(two[mq][:, None], tau[mq], 0.0)
            r_m, t_m = r_side.mean(axis=1), t_side.mean(axis=1)
            total = r_m + t_m
            live = total > 0
            alive, y, ny, r_side, t_side, r_m, total, weight = (
                alive[live], y[live], ny[live], r_side[live], t_side[live], r_m[live], total[live], weight[live])
            if len(alive) == 0:
                break
            refl = rng.random(len(alive)) < r_m / total
            p = np.where(refl, r_m / total, 1 - r_m / total)
            k = np.where(refl[:, None], r_side, t_side)
            weight = weight * k / p[:, None]
            nn = np.where(refl[:, None], ny, -ny)
            result[alive] += weight * direct(y, nn)
            # Russian roulette on the largest band's weight.
            wmax = weight.max(axis=1)
            keep_p = np.clip(wmax, 0.05, 1.0)
            keep = rng.random(len(alive)) < keep_p
            weight = weight[keep] / keep_p[keep][:, None]
            alive, o, nn = alive[keep], y[keep], nn[keep]
        return result

    n_poly = len(faces)
    chosen = np.sort(rng.choice(n_poly, size=min(a.polygons, n_poly), replace=False))
    # Triangles of each chosen polygon, for points uniform over it.
    by_poly = {}
    for ti, k in enumerate(owner):
        by_poly.setdefault(k, []).append(ti)
    jobs = []  # (polygon, side)
    for k in chosen:
        jobs.append((k, 0))
        if two[fmat[k]]:
            jobs.append((k, 1))
    per = a.samples
    est = {}
    chunk = max(1, a.batch // per)
    for j0 in range(0, len(jobs), chunk):
        part = jobs[j0 : j0 + chunk]
        xs, ns = [], []
        for k, side in part:
            tl = np.array(by_poly[k])
            ar = tri_area[tl]
            pick = tl[rng.choice(len(tl), size=per, p=ar / ar.sum())]
            u, v = rng.random(per), rng.random(per)
            flip = u + v > 1
            u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
            P = T[pick]
            xs.append(P[:, 0] + u[:, None] * (P[:, 1] - P[:, 0]) + v[:, None] * (P[:, 2] - P[:, 0]))
            ns.append(np.broadcast_to(pn[k] if side == 0 else -pn[k], (per, 3)))
        x = np.concatenate(xs)
        n = np.concatenate(ns)
        e = direct(x, n) + radiosity_along(x, n)
        for i, job in enumerate(part):
            s = e[i * per : (i + 1) * per]
            est[job] = (s.mean(axis=0), s.std(axis=0, ddof=1) / np.sqrt(per))
        print(f"{min(j0 + chunk, len(jobs))}/{len(jobs)} sides", file=sys.stderr)
    head = ["id", "area_m2"]
    for side in ("", "back_"):
        head += [f"irr_{side}{b}_W_m2" for b in bands] + [f"se_{side}{b}_W_m2" for b in bands]
    with open(a.out + ".tmp", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(head)
        for k in chosen:
            area = tri_area[np.array(by_poly[k])].sum()
            row = [int(k), f"{area:.7g}"]
            for side in (0, 1):
                if (k, side) in est:
                    m, se = est[(k, side)]
                    row += [f"{v:.7g}" for v in m] + [f"{v:.7g}" for v in se]
                else:
                    row += [""] * (2 * nb)
            w.writerow(row)
    os.replace(a.out + ".tmp", a.out)


if __name__ == "__main__":
    main()
