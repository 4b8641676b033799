#!/usr/bin/python3
"""Independent check of dirt's closest hits, in float64 with numpy.

    check_hits.py TRIS.npy RAYS.npy HITS.npy [--limit N] [--show K]

TRIS.npy  float32 (T, 9)  world-space vertices v0 v1 v2      (`dirt triangles`)
RAYS.npy  float32 (N, 8)  ox oy oz tmin dx dy dz tmax        (`dirt rays`)
HITS.npy  uint32  (N, 4)  prim, bits(t), bits(u), bits(v)    (`dirt trace`)

Every ray is tested against every triangle in float64 (vectorised over
triangles, rays in chunks) with the edge functions of the watertight test
(Woop, Benthin, Wald 2013; the same shear as dirt, evaluated in float64 on the
same float32 inputs). Each edge function comes with a bound on the error dirt's
float32 evaluation can make, so every (ray, triangle) pair is classified as

  definite hit   all three edge functions clearly of one sign, every barycentric
                 farther than 1e-6 from 0, t clearly inside [tmin, tmax];
  possible hit   on an edge or vertex, grazing, degenerate, or t at a range end;
  miss           everything else.

A ray is
  a clear hit    if the closest definite hit has no other definite or possible
                 hit within 1e-5 relative in t (plus the error bounds): dirt's
                 prim must equal it, |t - t64| <= max(1e-4 max(1, |t|), bound)
                 and u, v must agree within their error bounds;
  a clear miss   if no triangle is a definite or possible hit: dirt must miss;
  ambiguous      otherwise (edges, vertices, grazing rays, ties): a dirt hit must
                 be a definite or possible hit of its prim with t within
                 tolerance and no clearly closer definite hit; a dirt miss is
                 accepted only when no triangle is a definite hit.

Every dirt hit must also have tmin <= t <= tmax, and every miss must be the miss
record (0xFFFFFFFF, bits(+inf), 0, 0).

Prints "N passed, N failed" per class and in total; exits 1 on any failure,
2 on unusable input. Needs only Debian's python3-numpy.
"""

import argparse
import sys

import numpy as np

INVALID = 0xFFFFFFFF
EPS32 = float(np.finfo(np.float32).eps)
# Safety factor on the first-order rounding analysis of dirt's float32 edge
# functions (see edge_tolerance; the analysis itself gives a factor of 2).
EDGE_K = 8.0
BARY_MIN = 1e-6  # barycentric distance below which a hit is "on an edge"
TIE_REL = 1e-5  # relative t difference below which two hits are a tie
T_TOL = 1e-4  # required |t - t64| <= T_TOL * max(1, |t|) (or the error bound)
CHUNK_PAIRS = 1 << 18  # rays x triangles evaluated at once

DEFINITE, POSSIBLE = 2, 1


class InputError(Exception):
    pass


def load(path, kind, columns, what):
    try:
        a = np.load(path, allow_pickle=False)
    except Exception as e:  # noqa: BLE001 - any reason is reported the same way
        raise InputError(f"{path}: cannot read as .npy ({e})") from e
    if a.dtype.kind != kind or a.dtype.itemsize != 4:
        want = "float32" if kind == "f" else "uint32"
        raise InputError(f"{path}: dtype is {a.dtype}, expected {want} ({what})")
    if a.ndim != 2 or a.shape[1] != columns:
        raise InputError(f"{path}: shape is {a.shape}, expected (N, {columns}) ({what})")
    return np.ascontiguousarray(a.astype(a.dtype.newbyteorder("=")))


def analyse(tris, rays):
    """Classify every (ray, triangle) pair of a chunk.

    tris: (T, 3, 3) float64; rays: (C, 8) float64, all rays sharing one axis
    permutation. Returns a dict of (C, T) arrays: status, t, terr (inf where t is
    not known), [t_lo, t_hi] (where t can be), u, v, bary_err.
    """
    o = rays[:, 0:3]
    tmin = rays[:, 3:4]
    d = rays[:, 4:7]
    tmax = rays[:, 7:8]
    kx, ky, kz = axes(d[0])
    dz = d[:, kz : kz + 1]
    sx = d[:, kx : kx + 1] / dz
    sy = d[:, ky : ky + 1] / dz
    sz = 1.0 / dz

    sheared = []
    for j in range(3):
        p = tris[None, :, j, :] - o[:, None, :]  # (C, T, 3)
        pz = p[:, :, kz]
        x = p[:, :, kx] - sx * pz
        y = p[:, :, ky] - sy * pz
        mx = np.abs(p[:, :, kx]) + np.abs(sx * pz)  # magnitude behind x's rounding
        my = np.abs(p[:, :, ky]) + np.abs(sy * pz)
        sheared.append((x, y, mx, my, sz * pz))
    (ax, ay, amx, amy, az), (bx, by, bmx, bmy, bz), (cx, cy, cmx, cmy, cz) = sheared

    e0 = cx * by - cy * bx
    e1 = ax * cy - ay * cx
    e2 = bx * ay - by * ax
    tol0 = edge_tolerance(cx, cy, cmx, cmy, bx, by, bmx, bmy)
    tol1 = edge_tolerance(ax, ay, amx, amy, cx, cy, cmx, cmy)
    tol2 = edge_tolerance(bx, by, bmx, bmy, ax, ay, amx, amy)

    det = e0 + e1 + e2
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        pos = (e0 > tol0) & (e1 > tol1) & (e2 > tol2)
        neg = (e0 < -tol0) & (e1 < -tol1) & (e2 < -tol2)
        some_pos = (e0 > tol0) | (e1 > tol1) | (e2 > tol2)
        some_neg = (e0 < -tol0) | (e1 < -tol1) | (e2 < -tol2)
        adet = np.abs(det)
        bary_ok = (np.abs(e0) > BARY_MIN * adet) & (np.abs(e1) > BARY_MIN * adet) & (np.abs(e2) > BARY_MIN * adet)
        inside = (pos | neg) & bary_ok
        outside = some_pos & some_neg
        near = ~inside & ~outside

        tt = e0 * az + e1 * bz + e2 * cz
        t = tt / det
        u = e1 / det
        v = e2 / det
        # Error bounds. t = sum(b_i * z_i) with b_i = e_i / det summing to 1, so
        # an error d_i in e_i moves t by d_i * (z_i - t) / det; likewise for u, v.
        err_e = tol0 + tol1 + tol2
        margin = adet - err_e
        terr = (
            tol0 * np.abs(az - t) + tol1 * np.abs(bz - t) + tol2 * np.abs(cz - t)
        ) / margin + 4 * EPS32 * (np.abs(e0 * az) + np.abs(e1 * bz) + np.abs(e2 * cz)) / adet
        bary_err = (np.maximum(np.maximum(tol0, tol1), tol2) + err_e) / margin + 4 * EPS32
        t_known = np.isfinite(t) & np.isfinite(terr) & (margin > 0)
        terr = np.where(t_known, terr, np.inf)
        # Where t is not known, a hit (all b_i of one sign) still lies between
        # the vertices' ray parameters z_i.
        zlo = np.minimum(np.minimum(az, bz), cz)
        zhi = np.maximum(np.maximum(az, bz), cz)
        zslack = 4 * EPS32 * (np.abs(az) + np.abs(bz) + np.abs(cz))
        t_lo = np.where(t_known, t - terr, zlo - zslack)
        t_hi = np.where(t_known, t + terr, zhi + zslack)
        in_range = t_known & (t - tmin > terr) & (tmax - t > terr)
        out_range = (t_hi < tmin) | (t_lo > tmax)

    status = np.zeros(det.shape, dtype=np.int8)
    candidate = (inside | near) & ~out_range
    status[candidate] = POSSIBLE
    status[inside & in_range] = DEFINITE
    return {"status": status, "t": t, "terr": terr, "t_lo": t_lo, "t_hi": t_hi, "u": u, "v": v, "bary_err": bary_err}


def edge_tolerance(px, py, pmx, pmy, qx, qy, qmx, qmy):
    """Bound on dirt's float32 error in the edge function px * qy - py * qx.

    Each sheared coordinate carries an absolute error of about 2 EPS32 times the
    magnitude behind it (pmx: |p_kx| + |sx p_kz|, from v - o and the shear), so
    the products are off by that times the other factor, plus their own rounding.
    """
    first = pmx * np.abs(qy) + np.abs(px) * qmy + pmy * np.abs(qx) + np.abs(py) * qmx
    own = np.abs(px * qy) + np.abs(py * qx)
    second = pmx * qmy + pmy * qmx
    return EDGE_K * EPS32 * (first + own) + EDGE_K * EDGE_K * EPS32 * EPS32 * second


def axes(d):
    """dirt's axis permutation for a direction (largest |component| is z)."""
    a = np.abs(d)
    if a[0] >= a[1] and a[0] >= a[2]:
        kz = 0
    elif a[1] >= a[2]:
        kz = 1
    else:
        kz = 2
    kx = (kz + 1) % 3
    ky = (kx + 1) % 3
    if d[kz] < 0:
        kx, ky = ky, kx
    return kx, ky, kz


def perm_key(d):
    """Per-ray key of the permutation, vectorised (same rule as `axes`)."""
    a = np.abs(d)
    kz = np.where((a[:, 0] >= a[:, 1]) & (a[:, 0] >= a[:, 2]), 0, np.where(a[:, 1] >= a[:, 2], 1, 2))
    neg = d[np.arange(len(d)), kz] < 0
    return kz * 2 + neg


class Tally:
    def __init__(self):
        self.passed = {"clear hit": 0, "clear miss": 0, "ambiguous": 0}
        self.failed = {"clear hit": 0, "clear miss": 0, "ambiguous": 0}
        self.examples = []

    def record(self, cls, row, problem, show):
        if problem is None:
            self.passed[cls] += 1
        else:
            self.failed[cls] += 1
            if len(self.examples) < show:
                self.examples.append(f"row {row} ({cls}): {problem}")


def check_ray(row, ray, hit, a, i, ntris, tally, show):
    """Check ray `row` (index `i` in the chunk analysis `a`) against dirt's hit."""
    prim, tbits, ubits, vbits = (int(x) for x in hit)
    t_d, u_d, v_d = (float(np.array([b], dtype=np.uint32).view(np.float32)[0]) for b in (tbits, ubits, vbits))
    tmin, tmax = float(ray[3]), float(ray[7])
    status = a["status"][i]
    t = a["t"][i]
    terr = a["terr"][i]
    definite = np.nonzero(status == DEFINITE)[0]
    candidates = np.nonzero(status >= POSSIBLE)[0]

    best = None
    clear = False
    if len(definite):
        order = np.lexsort((definite, t[definite]))
        best = int(definite[order[0]])
        tb = t[best]
        others = candidates[candidates != best]
        reach = tb + TIE_REL * abs(tb) + terr[best]
        clear = not np.any(a["t_lo"][i, others] <= reach)
        cls = "clear hit" if clear else "ambiguous"
    else:
        cls = "clear miss" if len(candidates) == 0 else "ambiguous"

    def tol(k):
        return max(T_TOL * max(1.0, abs(t[k])), terr[k])

    problem = None
    if prim == INVALID:
        if (tbits, ubits, vbits) != (0x7F800000, 0, 0):
            problem = f"miss record is not (inf, 0, 0): t={t_d} u={u_d} v={v_d}"
        elif best is not None:
            problem = f"dirt misses, float64 hits prim {best} at t={t[best]:.9g}"
    elif prim >= ntris:
        problem = f"dirt prim {prim} is not a triangle (scene has {ntris})"
    elif not (tmin <= t_d <= tmax):
        problem = f"dirt t={t_d:.9g} outside [tmin, tmax] = [{tmin:.9g}, {tmax:.9g}]"
    elif cls == "clear miss":
        problem = f"dirt hits prim {prim} at t={t_d:.9g}, float64 finds no triangle near the ray"
    elif cls == "clear hit":
        if prim != best:
            problem = f"dirt prim {prim} t={t_d:.9g}, float64 prim {best} t={t[best]:.9g}"
        elif abs(t_d - t[best]) > tol(best):
            problem = f"prim {prim}: dirt t={t_d:.9g}, float64 t={t[best]:.9g} (tolerance {tol(best):.3g})"
        else:
            ue = a["bary_err"][i, best] + 1e-5
            if abs(u_d - a["u"][i, best]) > ue or abs(v_d - a["v"][i, best]) > ue:
                problem = (
                    f"prim {prim}: dirt (u, v) = ({u_d:.7g}, {v_d:.7g}), "
                    f"float64 ({a['u'][i, best]:.7g}, {a['v'][i, best]:.7g}) (tolerance {ue:.3g})"
                )
    else:  # ambiguous, dirt hits
        if status[prim] < POSSIBLE:
            problem = f"dirt hits prim {prim} at t={t_d:.9g}, which float64 clearly misses"
        elif np.isfinite(terr[prim]) and abs(t_d - t[prim]) > tol(prim):
            problem = f"prim {prim}: dirt t={t_d:.9g}, float64 t={t[prim]:.9g} (tolerance {tol(prim):.3g})"
        elif not np.isfinite(terr[prim]) and not (
            a["t_lo"][i, prim] - T_TOL * max(1.0, abs(a["t_lo"][i, prim]))
            <= t_d
            <= a["t_hi"][i, prim] + T_TOL * max(1.0, abs(a["t_hi"][i, prim]))
        ):
            problem = (
                f"prim {prim}: dirt t={t_d:.9g} is outside the triangle's span "
                f"[{a['t_lo'][i, prim]:.9g}, {a['t_hi'][i, prim]:.9g}] along the ray"
            )
        elif best is not None and t_d > t[best] + tol(best):
            problem = f"dirt prim {prim} t={t_d:.9g}, but prim {best} is clearly hit closer at t={t[best]:.9g}"
    tally.record(cls, row, problem, show)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("tris", help="TRIS.npy from `dirt triangles`")
    ap.add_argument("rays", help="RAYS.npy from `dirt rays`")
    ap.add_argument("hits", help="HITS.npy from `dirt trace`")
    ap.add_argument("--limit", type=int, default=None, help="check only the first N rays")
    ap.add_argument("--show", type=int, default=10, help="print up to K failures (default 10)")
    args = ap.parse_args(argv)

    try:
        tris32 = load(args.tris, "f", 9, "triangles")
        rays32 = load(args.rays, "f", 8, "rays")
        hits = load(args.hits, "u", 4, "hits")
    except InputError as e:
        print(f"check_hits: {e}", file=sys.stderr)
        return 2
    if len(hits) != len(rays32):
        print(f"check_hits: {len(rays32)} rays but {len(hits)} hits", file=sys.stderr)
        return 2
    n = len(rays32) if args.limit is None else min(args.limit, len(rays32))
    tris = tris32.astype(np.float64).reshape(-1, 3, 3)
    rays = rays32[:n].astype(np.float64)
    ntris = len(tris)
    print(f"check_hits: {n} rays against {ntris} triangles (float64 brute force)")

    tally = Tally()
    keys = perm_key(rays[:, 4:7]) if n else np.zeros(0, dtype=np.int64)
    chunk = max(1, CHUNK_PAIRS // max(1, ntris))
    for key in range(6):
        rows = np.nonzero(keys == key)[0]
        for start in range(0, len(rows), chunk):
            idx = rows[start : start + chunk]
            a = analyse(tris, rays[idx])
            for i, row in enumerate(idx):
                check_ray(int(row), rays32[row], hits[row], a, i, ntris, tally, args.show)

    for line in tally.examples:
        print(f"  FAIL {line}")
    for cls in ("clear hit", "clear miss", "ambiguous"):
        print(f"  {cls + ':':12} {tally.passed[cls]:8} passed, {tally.failed[cls]} failed")
    passed = sum(tally.passed.values())
    failed = sum(tally.failed.values())
    print(f"check_hits: {passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
