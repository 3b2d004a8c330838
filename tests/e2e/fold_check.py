#!/usr/bin/env python3
"""Independent fold check of a spinvalence build, "as a fabricator would do it".

Reads only the build's output files (frame.json, strips.json, strips/<id>.dxf)
and uses its own geometry (numpy + ezdxf); nothing from the project is imported.

  python3 fold_check.py DIR [--min-overlap 25] [--json OUT] [--step 0.05]

Checks
  1. legs: for every leg j of every unit the pins are found in the DXF (centre of
     the narrowest web between the two slots bounding the leg: hub neck = inner
     web near corner j, rim neck = outer web near corner j+1).  Hub pins are
     moved to 3D with the rigid motion flat tile -> frame.json `hub`, rim pins
     with flat tile -> frame.json `primary`.  | |H-R| - |h-r| | <= 0.5 mm.
     Distance of our pins to frame.json `pins` must be <= 0.5 mm too.
  2. hub laps: hub plate rebuilt from the DXF slots, its corner facing the link
     moved to 3D, lap = (tip_f - tip_g) . e >= --min-overlap and within 0.1 mm
     of links[].hub_overlap.  The two hub plates (seen along one's normal) overlap
     along the line of centres by >= --min-overlap too: where the tips pass each
     other offset sideways they overlap by less than the lap.
  3. (informational) largest primary gap and count of links whose facing
     primary sides pass through each other.
  4. bridges: each primary plate as the OUTSIDE outline cuts it (per tile side the
     longest straight outline segment along it, on it or up to 5 mm inside); a
     bridge is where the outline crosses the joint line of two units of a strip
     (two crossings).  At both its sides the bridge's ends on the two plates are
     moved to 3D with their plates: | folded - flat | <= 0.5 mm; bend (in the
     first plate's plane) and twist of the joint line within frame.json's
     params.joint_limits.
  5. welds between strips: from the joint point (links[].joint.along on the first
     unit's facing side) to the other plate as cut, thickened to t either side of
     its mid-plane: <= 1.5 mm, and within 0.1 mm of links[].joint.gap.
  6. collisions: how far each facing edge of two strips' plates reaches into the
     other plate (depth inside its outline and inside its slab t either side,
     the smaller; the exact largest along the edge): <= 0.1 mm.  The same across
     every bridge's joint slot: two plates of one strip turned in their plane meet
     at the end of their sides away from the bridge.
  7. hub plates at their laps lie one on the other: over the overlap of the two
     hub plates (seen along one's normal) the height of one mid-plane over the
     other stays >= t (or <= -t); how far from it, <= 0.1 mm.  Where frame.json
     says params.hub_laps_touch, the closest gap between the two over every lap
     <= 1.5 mm (they touch somewhere).  Informational: the widest gap between the
     two over a lap, the closest elsewhere, and how deep each leg's centre
     line (hub neck to rim neck) runs into the neighbour's hub plate there, and how
     deep the lower plate's cuts (the relief for that leg) reach under the upper plate.

Exit status: 0 all pass, 1 some check failed, 2 input files unreadable.
"""
import argparse
import json
import math
import os
import sys

# one BLAS thread: the distance matrices here are small, threads only thrash
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

try:
    import numpy as np  # noqa: E402
except ImportError:  # pragma: no cover
    print("fold_check: numpy is required", file=sys.stderr)
    sys.exit(2)

LEG_TOL = 0.5
PIN_TOL = 0.5
LAP_CLAIM_TOL = 0.1
KABSCH_TOL = 1e-3
BRIDGE_TOL = 0.5     # bridge span, folded - flat (mm)
WELD_TOL = 1.5       # plates of neighbouring strips apart at their weld (mm)
REACH_TOL = 0.1      # plates into each other (mm)


# ----------------------------------------------------------------- geometry

def flatten_lwpolyline(pts, step):
    """pts: (n,3) array x,y,bulge of a closed polyline -> (m,2) dense points
    (closed; last point not repeated), and list of straight segments."""
    n = len(pts)
    out = []
    lines = []
    prims = []
    for i in range(n):
        p = pts[i, :2]
        q = pts[(i + 1) % n, :2]
        b = pts[i, 2]
        d = q - p
        c = math.hypot(d[0], d[1])
        if c < 1e-12:
            continue
        if abs(b) < 1e-9:
            k = max(1, int(math.ceil(c / step)))
            t = np.arange(k)[:, None] / k
            out.append(p + t * d)
            lines.append((p.copy(), q.copy()))
            prims.append(("L", p.copy(), q.copy()))
        else:
            theta = 4.0 * math.atan(b)
            m = 0.5 * (p + q)
            nrm = np.array([-d[1], d[0]]) / c
            ctr = m + nrm * (0.5 * c) * (1.0 - b * b) / (2.0 * b)
            r = math.hypot(*(p - ctr))
            a0 = math.atan2(p[1] - ctr[1], p[0] - ctr[0])
            k = max(1, int(math.ceil(r * abs(theta) / step)))
            a = a0 + theta * np.arange(k) / k
            out.append(ctr + r * np.stack([np.cos(a), np.sin(a)], 1))
            prims.append(("A", ctr, r, a0, theta, p.copy(), q.copy()))
    return np.concatenate(out, 0), lines, prims


def prim_len(pr):
    if pr[0] == "L":
        return float(np.linalg.norm(pr[2] - pr[1]))
    return abs(pr[2] * pr[4])


def prim_eval(pr, u):
    """Points at parameters u in [0, 1] along a primitive."""
    u = np.asarray(u, float)[:, None]
    if pr[0] == "L":
        return pr[1] + u * (pr[2] - pr[1])
    a = pr[3] + pr[4] * u[:, 0]
    return pr[1] + pr[2] * np.stack([np.cos(a), np.sin(a)], 1)


def prim_param(pr, x):
    """Parameter in [0, 1] of the point of the primitive nearest x."""
    if pr[0] == "L":
        d = pr[2] - pr[1]
        return min(1.0, max(0.0, float(np.dot(x - pr[1], d) / np.dot(d, d))))
    v = x - pr[1]
    ang = math.atan2(v[1], v[0]) - pr[3]
    th = pr[4]
    rel = (ang % (2 * math.pi)) if th > 0 else ((-ang) % (2 * math.pi))
    u = rel / abs(th)
    if u <= 1.0:
        return u
    # outside the sweep: the nearer end
    return 0.0 if np.dot(x - pr[5], x - pr[5]) <= np.dot(x - pr[6], x - pr[6]) else 1.0


def sample_near(prims, x, rad, step):
    """Points of the contour within about rad of x, spaced step (along each primitive)."""
    out = []
    for pr in prims:
        L = prim_len(pr)
        if L < 1e-12:
            continue
        u0 = prim_param(pr, x)
        y = prim_eval(pr, [u0])[0]
        if np.linalg.norm(y - x) > rad + 1e-12 and np.linalg.norm(y - x) > 1.0:
            continue
        du = rad / L
        lo, hi = max(0.0, u0 - du), min(1.0, u0 + du)
        k = max(2, int(math.ceil((hi - lo) * L / step)) + 1)
        out.append(prim_eval(pr, np.linspace(lo, hi, k)))
    return np.concatenate(out, 0) if out else None


def polish(prims_a, prims_b, pa, pb):
    """Refine a closest pair of the two exact contours (lines and arcs) by
    resampling ever finer around the current pair (+-0.2 mm at 5 um spacing,
    then down to 0.6 nm spacing): the narrowest-web point to ~1e-6 mm."""
    for rad, step in ((0.2, 5e-3), (0.01, 2.5e-4), (5e-4, 1.25e-5), (2.5e-5, 6e-7)):
        A = sample_near(prims_a, pa, rad, step)
        B = sample_near(prims_b, pb, rad, step)
        if A is None or B is None:
            break
        o = 0.5 * (pa + pb)
        A0, B0 = A - o, B - o
        d2 = ((A0[:, None, :] - B0[None, :, :]) ** 2).sum(-1)
        k = int(np.argmin(d2))
        u, v = divmod(k, len(B))
        if d2[u, v] <= float(np.dot(pa - pb, pa - pb)) + 1e-15:
            pa, pb = A[u], B[v]
    return pa, pb


def kabsch_2d_to_3d(P2, Q3):
    """Rigid motion (R 3x3, t) with R @ [x,y,0] + t ~= Q.  Returns R, t, rms residual."""
    P = np.hstack([np.asarray(P2, float), np.zeros((len(P2), 1))])
    Q = np.asarray(Q3, float)
    pc, qc = P.mean(0), Q.mean(0)
    H = (P - pc).T @ (Q - qc)
    U, S, Vt = np.linalg.svd(H)
    dd = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
    D = np.diag([1.0, 1.0, dd])
    R = Vt.T @ D @ U.T
    t = qc - R @ pc
    res = np.sqrt(np.mean(np.sum((P @ R.T + t - Q) ** 2, 1)))
    return R, t, res


def apply(Rt, p2):
    R, t = Rt[0], Rt[1]
    p = np.asarray(p2, float)
    return R[:, :2] @ p + t


def seg_seg(p1, q1, p2, q2):
    """Closest points of 3D segments p1q1 and p2q2 (Ericson)."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e, f = np.dot(d1, d1), np.dot(d2, d2), np.dot(d2, r)
    c, b = np.dot(d1, r), np.dot(d1, d2)
    den = a * e - b * b
    s = min(1.0, max(0.0, (b * f - c * e) / den)) if den > 1e-12 else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        t, s = 0.0, min(1.0, max(0.0, -c / a))
    elif t > 1.0:
        t, s = 1.0, min(1.0, max(0.0, (b - c) / a))
    return p1 + s * d1, p2 + t * d2


def seg_pierces_quad(b0, b1, Q):
    """Does segment b0b1 cross the plane of planar quad Q inside Q?"""
    c = Q.mean(0)
    n = np.cross(Q[2] - Q[0], Q[3] - Q[1])
    n /= np.linalg.norm(n)
    s0, s1 = np.dot(b0 - c, n), np.dot(b1 - c, n)
    if s0 * s1 > 0 or s0 == s1:
        return False
    x = b0 + (s0 / (s0 - s1)) * (b1 - b0)
    u = Q[1] - Q[0]
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    q2 = np.array([[np.dot(p - c, u), np.dot(p - c, v)] for p in Q])
    return point_in_convex(q2, np.array([np.dot(x - c, u), np.dot(x - c, v)]))


def depth_in(poly, p):
    """Distance from p, inside the convex polygon poly, to its outline."""
    n = len(poly)
    depth = math.inf
    for i in range(n):
        a = poly[(i + 1) % n] - poly[i]
        d = p - poly[i]
        depth = min(depth, abs(a[0] * d[1] - a[1] * d[0]) / np.linalg.norm(a))
    return depth


def point_in_convex(poly, p):
    s = None
    n = len(poly)
    for i in range(n):
        a, b = poly[i], poly[(i + 1) % n]
        cr = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
        if abs(cr) < 1e-12:
            continue
        if s is None:
            s = cr > 0
        elif (cr > 0) != s:
            return False
    return True


def line_intersect(a, b):
    """a, b: (p, q) segments -> intersection of their infinite lines."""
    p, r = a[0], a[1] - a[0]
    q, s = b[0], b[1] - b[0]
    den = r[0] * s[1] - r[1] * s[0]
    if abs(den) < 1e-12:
        return None
    w = q - p
    t = (w[0] * s[1] - w[1] * s[0]) / den
    return p + t * r


def cyclic_runs(mask):
    """Index runs (lists) of True in a cyclic boolean array."""
    n = len(mask)
    if not mask.any():
        return []
    if mask.all():
        return [list(range(n))]
    start = int(np.argmin(mask))  # a False position
    runs, cur = [], []
    for k in range(1, n + 1):
        i = (start + k) % n
        if mask[i]:
            cur.append(i)
        elif cur:
            runs.append(cur)
            cur = []
    if cur:
        runs.append(cur)
    return runs


def near_prims(prims, x, rad):
    out = []
    for pr in prims:
        if pr[0] == "L":
            lo = np.minimum(pr[1], pr[2]); hi = np.maximum(pr[1], pr[2])
        else:
            lo = pr[1] - pr[2]; hi = pr[1] + pr[2]
        if np.all(x >= lo - rad) and np.all(x <= hi + rad):
            out.append(pr)
    return out or prims


def sqdist(A, B):
    d = (A * A).sum(1)[:, None] + (B * B).sum(1)[None, :] - 2.0 * (A @ B.T)
    return np.maximum(d, 0.0)


def necks_between(fa, fb, K, thr, prims_a=None, prims_b=None):
    """Narrow webs between dense closed contours fa, fb (coarse stride K).
    Returns list of (width, midpoint(2,), pa, pb)."""
    o = fa[0]
    ca, cb = fa[::K] - o, fb[::K] - o
    D2 = sqdist(ca, cb)
    near = D2.min(1) < thr * thr
    res = []
    na, nb = len(fa), len(fb)
    W = 3 * K
    for run in cyclic_runs(near):
        sub = D2[run]
        k = int(np.argmin(sub))
        i0, j0 = run[k // sub.shape[1]], k % sub.shape[1]
        ia = np.arange(i0 * K - W, i0 * K + W + 1) % na
        ib = np.arange(j0 * K - W, j0 * K + W + 1) % nb
        A, B = fa[ia], fb[ib]
        d2 = sqdist(A - fa[ia[0]], B - fa[ia[0]])
        k = int(np.argmin(d2))
        u, v = divmod(k, len(B))
        pa, pb = A[u], B[v]
        if prims_a is not None:
            pa, pb = polish(near_prims(prims_a, pa, 5.0), near_prims(prims_b, pb, 5.0), pa, pb)
        res.append((float(np.linalg.norm(pa - pb)), 0.5 * (pa + pb), pa, pb))
    # merge duplicates (same web seen from two runs)
    merged = []
    for r in sorted(res, key=lambda r: r[0]):
        if all(np.linalg.norm(r[1] - m[1]) > 5.0 for m in merged):
            merged.append(r)
    return merged


def side_frame(T, k):
    """Side k of the convex flat tile T: its start, unit direction, outward unit normal and
    length."""
    a, b = T[k], T[(k + 1) % len(T)]
    ln = float(np.linalg.norm(b - a))
    d = (b - a) / ln
    n = np.array([d[1], -d[0]])
    if np.dot(n, 0.5 * (a + b) - T.mean(0)) < 0:
        n = -n
    return a, d, n, ln


PLATE_INSET_MAX = 5.0


def plate_as_cut(T, lines):
    """The primary plate of flat tile T as the strip outline cuts it: per side the longest
    straight outline segment parallel to the side (within 0.6 deg), on it or up to 5 mm
    inside; the corners where those lines meet (fillets ignored).  (quad, per-side lines)
    or None when a side has no such segment."""
    edge = []
    for k in range(4):
        a, d, n, ln = side_frame(T, k)
        best = None
        for p, q in lines:
            v = q - p
            lv = float(np.linalg.norm(v))
            if lv < 1.0 or abs(v[0] * d[1] - v[1] * d[0]) / lv > 0.01:
                continue
            op, oq = np.dot(p - a, n), np.dot(q - a, n)
            if not (-PLATE_INSET_MAX <= min(op, oq) and max(op, oq) <= 0.01):
                continue
            if not 0.0 < np.dot(0.5 * (p + q) - a, d) < ln:
                continue
            if best is None or lv > best[0]:
                best = (lv, p, q)
        if best is None:
            return None
        edge.append((best[1], best[2]))
    quad = [line_intersect(edge[(k - 1) % 4], edge[k]) for k in range(4)]
    if any(c is None for c in quad):
        return None
    return np.array(quad), edge


def foot(line, x):
    """Foot of x on the infinite line (p, q)."""
    p, q = line
    d = (q - p) / np.linalg.norm(q - p)
    return p + np.dot(x - p, d) * d


def crossings(T, k, dense, margin=3.0):
    """Where the closed dense outline crosses the line of T's side k, as distances along the
    side, more than `margin` from its ends (a bridge's two sides)."""
    a, d, n, ln = side_frame(T, k)
    out = []
    for P in dense:
        Q = np.roll(P, -1, 0)
        op, oq = (P - a) @ n, (Q - a) @ n
        for i in np.nonzero(op * oq < 0)[0]:
            x = P[i] + (op[i] / (op[i] - oq[i])) * (Q[i] - P[i])
            u = float(np.dot(x - a, d))
            if margin < u < ln - margin:
                out.append(u)
    return sorted(out)


def plate_frame(Q):
    """A 3D planar quad: centre, unit normal, in-plane axes and its 2D corners."""
    c = Q.mean(0)
    n = np.cross(Q[2] - Q[0], Q[3] - Q[1])
    n /= np.linalg.norm(n)
    u = Q[1] - Q[0]
    u -= n * np.dot(u, n)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    return c, n, u, v, np.array([[np.dot(p - c, u), np.dot(p - c, v)] for p in Q])


def signed_depth(poly, p):
    """Distance from p to the outline of the convex polygon poly: positive inside, negative
    outside."""
    dmin = math.inf
    for i in range(len(poly)):
        a, b = poly[i], poly[(i + 1) % len(poly)]
        ab = b - a
        t = min(1.0, max(0.0, float(np.dot(p - a, ab) / np.dot(ab, ab))))
        dmin = min(dmin, float(np.linalg.norm(p - (a + t * ab))))
    return dmin if point_in_convex(poly, p) else -dmin


def plate_gap(x, pf, t):
    """From x to the plate `pf` (plate_frame) thickened to t either side of its mid-plane:
    zero edge to edge in one plane, and for an edge resting on the face."""
    c, n, u, v, q2 = pf
    h = float(np.dot(x - c, n))
    sd = signed_depth(q2, np.array([np.dot(x - c, u), np.dot(x - c, v)]))
    return math.hypot(max(0.0, -sd), max(0.0, abs(h) - t))


def segment_reach(x0, x1, pf, t):
    """How deep the segment x0 x1 reaches into the plate `pf` (plate_frame): the largest,
    over its points, of the smaller of the depth inside the outline and the depth inside the
    slab t either side of the mid-plane; 0 when it stays clear.  Along the segment each of
    those is linear, so the largest of their smallest lies at an end or at a crossing of
    two of them: all are tried."""
    c, n, u, v, q2 = pf
    area = sum(q2[i][0] * q2[(i + 1) % 4][1] - q2[(i + 1) % 4][0] * q2[i][1] for i in range(4))
    lines = []   # (value at x0, change from x0 to x1)
    p0 = np.array([np.dot(x0 - c, u), np.dot(x0 - c, v)])
    p1 = np.array([np.dot(x1 - c, u), np.dot(x1 - c, v)])
    for i in range(4):
        e = q2[(i + 1) % 4] - q2[i]
        inward = np.array([-e[1], e[0]]) / np.linalg.norm(e) * (1.0 if area > 0 else -1.0)
        lines.append((float(np.dot(p0 - q2[i], inward)), float(np.dot(p1 - p0, inward))))
    h0, h1 = float(np.dot(x0 - c, n)), float(np.dot(x1 - c, n))
    lines += [(t - h0, -(h1 - h0)), (t + h0, h1 - h0)]

    def at(s):
        return min(a + b * s for a, b in lines)
    cand = [0.0, 1.0]
    for i in range(len(lines)):
        for j in range(i + 1, len(lines)):
            slope = lines[i][1] - lines[j][1]
            if abs(slope) > 1e-15:
                s_ = (lines[j][0] - lines[i][0]) / slope
                if 0.0 <= s_ <= 1.0:
                    cand.append(s_)
    return max(0.0, max(at(s_) for s_ in cand))


def ccw(q):
    """The flat polygon q (points), counter-clockwise."""
    q = [np.asarray(p, float) for p in q]
    a = sum(q[i][0] * q[(i + 1) % len(q)][1] - q[(i + 1) % len(q)][0] * q[i][1] for i in range(len(q)))
    return q[::-1] if a < 0 else q


def clip_convex(P, Q):
    """Part of convex polygon P inside convex counter-clockwise polygon Q (2D)."""
    out = [np.asarray(p, float) for p in P]
    for i in range(len(Q)):
        a, b = Q[i], Q[(i + 1) % len(Q)]
        e = b - a
        inp, out = out, []
        if not inp:
            break
        for j in range(len(inp)):
            c, d = inp[j], inp[(j + 1) % len(inp)]
            sc = e[0] * (c[1] - a[1]) - e[1] * (c[0] - a[0])
            sd = e[0] * (d[1] - a[1]) - e[1] * (d[0] - a[0])
            if sc >= 0:
                out.append(c)
            if (sc >= 0) != (sd >= 0):
                out.append(c + (d - c) * (sc / (sc - sd)))
    return out


def lap_heights(A, B):
    """Hub plates A, B (3D quads) that lap: over their overlap seen along B's normal,
    the lowest and highest height of A's mid-plane above B's; None without overlap."""
    cb, nb, ub, vb, qb = plate_frame(B)
    ca, na, _, _, _ = plate_frame(A)
    if abs(np.dot(na, nb)) < 1e-6:
        return None
    qb = ccw(qb)
    qa = [np.array([np.dot(p - cb, ub), np.dot(p - cb, vb)]) for p in A]
    ov = clip_convex(qa, qb)
    if len(ov) < 3:
        return None
    hs = []
    for x in ov:
        X = cb + x[0] * ub + x[1] * vb
        hs.append(float(np.dot(na, ca - X) / np.dot(na, nb)))
    return min(hs), max(hs)


def overlap_along(A, B):
    """Hub plates A, B (3D quads) that lap: the length of their overlap seen along B's
    normal, measured along the line from A's centre to B's; 0 without overlap."""
    cb, nb, ub, vb, qb = plate_frame(B)
    ca = plate_frame(A)[0]
    qb = ccw(qb)
    qa = ccw([np.array([np.dot(p - cb, ub), np.dot(p - cb, vb)]) for p in A])
    ov = clip_convex(qa, qb)
    if len(ov) < 3:
        return 0.0
    d = np.array([np.dot(cb - ca, ub), np.dot(cb - ca, vb)])
    d = d / np.linalg.norm(d)
    s = [float(np.dot(x, d)) for x in ov]
    return max(s) - min(s)


def turn(Ra, Rb, d):
    """Bend (in plate a's plane) and twist (out of it), radians, between the joint direction
    d (flat) carried by rotation Ra and by Rb; a pure fold about d gives (0, 0)."""
    e = Ra[:, :2] @ d
    g = Rb[:, :2] @ d
    n = Ra[:, 2]
    bend = math.atan2(float(np.dot(np.cross(n, e), g)), float(np.dot(e, g)))
    twist = math.asin(max(-1.0, min(1.0, float(np.dot(n, g)))))
    return bend, twist


# ----------------------------------------------------------------- main

class InputError(Exception):
    pass


def inset_quad(Q, delta):
    """The convex quad Q (flat, either orientation) with every side moved inward by delta."""
    Q = np.asarray(Q, float)
    c = Q.mean(0)
    lines = []
    for i in range(4):
        a, b = Q[i], Q[(i + 1) % 4]
        d = (b - a) / np.linalg.norm(b - a)
        n = np.array([-d[1], d[0]])
        if np.dot(c - a, n) < 0:
            n = -n
        lines.append((a + n * delta, d))
    out = []
    for i in range(4):
        (p, d), (q, e) = lines[(i + 3) % 4], lines[i]
        den = d[0] * e[1] - d[1] * e[0]
        s_ = ((q - p)[0] * e[1] - (q - p)[1] * e[0]) / den
        out.append(p + d * s_)
    return np.array(out)


def leg_plate(T, cut, joint, hub_pin, rim_pin, folds, hub_m, pri_m, k):
    """Leg k of the unit of flat tile T as a plate (world quad): its body, the band between
    its two slots along side k from its hub neck to where the slot crosses its end, put on
    its two pins and turned about the line between them so that its necks' fold lines, as
    the leg carries them, lie as near as they can to the same lines as the hub and the rim
    carry them."""
    rim, slot, legw = float(cut["rim"]), float(cut["slot"]), float(cut["leg"])
    q = inset_quad(T, joint / 2.0)
    outer, inner = inset_quad(q, rim + slot), inset_quad(q, rim + slot + legw)
    iq, oq = inset_quad(q, rim + 1.5 * slot + legw), inset_quad(q, rim + 0.5 * slot)
    k1, k2 = (k + 1) % 4, (k + 2) % 4
    d = (q[k1] - q[k]) / np.linalg.norm(q[k1] - q[k])
    # where slot k crosses the end of leg k: its inner run's line meets the outer track of
    # the next side
    d1 = (q[k2] - q[k1]) / np.linalg.norm(q[k2] - q[k1])
    den = d[0] * d1[1] - d[1] * d1[0]
    w = oq[k1] - iq[k]
    x = iq[k] + d * ((w[0] * d1[1] - w[1] * d1[0]) / den)
    start = np.dot(hub_pin - outer[k], d)
    end = np.dot(x - outer[k], d) - slot / 2.0
    if end <= start:
        return None

    def on(line, t):
        e = (line[k1] - line[k]) / np.linalg.norm(line[k1] - line[k])
        return line[k] + e * ((t - np.dot(line[k] - outer[k], d)) / np.dot(e, d))
    body = [on(outer, start), on(outer, end), on(inner, end), on(inner, start)]
    H, R = apply(hub_m, hub_pin), apply(pri_m, rim_pin)
    e1 = np.append((rim_pin - hub_pin) / np.linalg.norm(rim_pin - hub_pin), 0.0)
    e2 = np.cross([0.0, 0.0, 1.0], e1)
    a_ = (R - H) / np.linalg.norm(R - H)
    b0 = np.cross(a_, [0.0, 0.0, 1.0])
    if np.linalg.norm(b0) < 1e-6:
        b0 = np.cross(a_, [1.0, 0.0, 0.0])
    b0 /= np.linalg.norm(b0)
    c0 = np.cross(a_, b0)
    sc = ss = 0.0
    for fl, M in ((folds[0], hub_m[0]), (folds[1], pri_m[0])):
        f3 = np.append(fl / np.linalg.norm(fl), 0.0)
        F = M @ f3
        f2 = np.dot(f3, e2)
        sc += f2 * np.dot(b0, F)
        ss += f2 * np.dot(c0, F)
    psi = math.atan2(ss, sc)
    b = b0 * math.cos(psi) + c0 * math.sin(psi)
    Rl = np.column_stack([a_, b, np.cross(a_, b)]) @ np.column_stack([e1, e2, [0.0, 0.0, 1.0]]).T
    return np.array([H + Rl @ np.append(p - hub_pin, 0.0) for p in body])


def hull2(P):
    """Convex hull of 2D points, counter-clockwise."""
    P = sorted(set((round(float(p[0]), 9), round(float(p[1]), 9)) for p in P))
    if len(P) < 3:
        return [np.array(p) for p in P]

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    lower, upper = [], []
    for p in P:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(P):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return [np.array(p) for p in lower[:-1] + upper[:-1]]


def section_inside(leg, plate, t):
    """The part of the leg slab (quad `leg`, t through) inside the slab of `plate` (world
    quad, t through) and inside its outline, in the plate's frame: (frame, counter-clockwise
    outline, section); None when nothing of the leg is there."""
    pf = plate_frame(plate)
    c, n, u, v, q2 = pf
    nl = np.cross(leg[2] - leg[0], leg[3] - leg[1])
    nl /= np.linalg.norm(nl)
    corners = [p + nl * o for o in (-t / 2, t / 2) for p in leg]
    edges = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
             (0, 4), (1, 5), (2, 6), (3, 7)]
    h = [float(np.dot(p - c, n)) for p in corners]
    pts = [corners[i] for i in range(8) if abs(h[i]) <= t / 2]
    for i, j in edges:
        for level in (-t / 2, t / 2):
            if (h[i] - level) * (h[j] - level) < 0:
                pts.append(corners[i] + (corners[j] - corners[i]) * ((level - h[i]) / (h[j] - h[i])))
    sec = hull2([np.array([np.dot(p - c, u), np.dot(p - c, v)]) for p in pts])
    if len(sec) < 3:
        return None
    outline = ccw(q2)
    inside = clip_convex(sec, outline)
    if len(inside) < 3:
        return None
    return pf, np.array(outline), inside


def leg_section(leg, plate, hub_m, t):
    """The leg's section through the hub plate `plate` (section_inside), in the plate's flat
    frame (through its motion `hub_m`); [] when none."""
    found = section_inside(leg, plate, t)
    if found is None:
        return []
    (c, _, u, v, _), _, inside = found
    R, tt = hub_m[0], hub_m[1]
    return [(R.T @ (c + u * p[0] + v * p[1] - tt))[:2] for p in inside]


def rim_reach_of(leg, plate, rim_w, t):
    """How deep the leg plate runs into the rim of the primary plate `plate` (world quad as
    cut, t through): its section through the plate's slab against the band rim_w wide
    inside the plate's outline."""
    found = section_inside(leg, plate, t)
    if found is None:
        return 0.0
    _, outline, inside = found
    return into_steel(inside, outline, [inset_quad(outline, rim_w)])


def inside_polygon(poly, P):
    """Which of the points P (n x 2) lie inside the closed polygon poly (even-odd rule)."""
    a = np.asarray(poly, float)[:, :2]
    b = np.roll(a, -1, axis=0)
    if len(P) == 0:
        return np.zeros(0, bool)
    # a ray to +x crosses only edges beside the points' span and not wholly left of it
    lo, hi = P.min(0), P.max(0)
    keep = ((np.maximum(a[:, 1], b[:, 1]) >= lo[1]) & (np.minimum(a[:, 1], b[:, 1]) <= hi[1])
            & (np.maximum(a[:, 0], b[:, 0]) >= lo[0]))
    a, b = a[keep], b[keep]
    y = P[:, 1][:, None]
    x = P[:, 0][:, None]
    cond = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = a[None, :, 0] + (y - a[None, :, 1]) / (b[None, :, 1] - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0])
    return (np.count_nonzero(cond & (x < xc), axis=1) % 2) == 1


def distance_to_outline(poly, P):
    """Distance of each point of P (n x 2) to the closed polygon poly's edges."""
    a = np.asarray(poly, float)[:, :2]
    e = np.roll(a, -1, axis=0) - a
    ee = np.maximum((e * e).sum(1), 1e-300)
    tt = np.clip((((P[:, None, :] - a[None]) * e[None]).sum(2)) / ee[None], 0.0, 1.0)
    foot = a[None] + tt[:, :, None] * e[None]
    return np.linalg.norm(P[:, None, :] - foot, axis=2).min(1)


def grid_in(poly, step):
    """Points every `step` inside the flat polygon poly, and its corners."""
    S = np.asarray(poly, float)
    lo, hi = S.min(0), S.max(0)
    xs, ys = np.meshgrid(np.arange(lo[0], hi[0] + step, step), np.arange(lo[1], hi[1] + step, step))
    G = np.column_stack([xs.ravel(), ys.ravel()])
    return np.vstack([G[inside_polygon(S, G)], S])


def thinned(cuts):
    return [np.asarray(cu, float)[::5 if len(cu) > 50 else 1, :2] for cu in cuts]


def into_steel(sec, outline, cuts, step=0.5):
    """How deep the flat convex polygon sec lies in a plate's steel: inside the quad
    outline and outside every cut (dense closed contours, taken every ~0.25 mm). Sampled
    every half millimetre."""
    if len(sec) < 3 or outline is None:
        return 0.0
    P = grid_in(sec, step)
    cuts = thinned(cuts)
    free = np.zeros(len(P), bool)
    for cu in cuts:
        free |= inside_polygon(cu, P)
    P = P[~free]
    if len(P) == 0:
        return 0.0
    d = np.full(len(P), np.inf)
    for poly in [np.asarray(outline, float)] + cuts:
        d = np.minimum(d, distance_to_outline(poly, P))
    return float(d.max())


def cut_under(upper, outline, cuts, step=0.25):
    """How deep the cuts of a hub plate (flat quad `outline`, its cut contours `cuts`)
    reach under the plate lying on it at a lap (`upper`, flat, in the same frame): the
    deepest point inside both plates (0.2 mm inside `outline`, past the round-off of its
    slots) that a cut took out, from `upper`'s edge."""
    upper = np.array(ccw(upper))
    lap = clip_convex(upper, ccw(inset_quad(outline, 0.2)))
    if len(lap) < 3:
        return 0.0
    lap = np.array(lap)
    deepest = 0.0
    for cu in cuts:
        cu = np.asarray(cu, float)[:, :2]
        # a cut into the lap has points of its contour (every ~0.25 mm) there: the grid
        # covers those and half a millimetre round them
        near = cu[inside_polygon(lap, cu)]
        if len(near) == 0:
            continue
        lo, hi = near.min(0) - 0.5, near.max(0) + 0.5
        xs, ys = np.meshgrid(np.arange(lo[0], hi[0] + step, step), np.arange(lo[1], hi[1] + step, step))
        P = np.vstack([np.column_stack([xs.ravel(), ys.ravel()]), near])
        P = P[inside_polygon(lap, P)]
        P = P[inside_polygon(cu, P)]
        if len(P):
            deepest = max(deepest, float(distance_to_outline(upper, P).max()))
    return deepest


def load_inputs(d):
    try:
        with open(os.path.join(d, "frame.json")) as f:
            frame = json.load(f)
        with open(os.path.join(d, "strips.json")) as f:
            strips = json.load(f)
    except Exception as e:  # noqa
        raise InputError("cannot read frame.json/strips.json: %s" % e)
    if frame.get("format") != "spin-valence/frame" or frame.get("version") != 2:
        raise InputError("frame.json is not spin-valence/frame version 2 (%r %r)"
                         % (frame.get("format"), frame.get("version")))
    return frame, strips


def read_cut(path):
    """Closed LWPOLYLINEs (x, y, bulge arrays) of the strip DXF: (INSIDE, OUTSIDE)."""
    try:
        import ezdxf
    except ImportError:
        raise InputError("ezdxf is required to read %s" % path)
    layers = {"INSIDE": [], "OUTSIDE": []}

    def keep(e):
        lay = e.dxf.layer.upper()
        if lay in layers:
            layers[lay].append(np.array(list(e.get_points("xyb")), float))
    try:
        from ezdxf.addons import iterdxf  # fast single pass, modelspace only
        with open(path, "rb") as fh:
            for e in iterdxf.single_pass_modelspace(fh, types=["LWPOLYLINE"]):
                keep(e)
        return layers["INSIDE"], layers["OUTSIDE"]
    except Exception:  # noqa  -- fall back to the full reader
        layers = {"INSIDE": [], "OUTSIDE": []}
    try:
        doc = ezdxf.readfile(path)
    except Exception as e:  # noqa
        raise InputError("cannot read %s: %s" % (path, e))
    for e in doc.modelspace():
        if e.dxftype() == "LWPOLYLINE":
            keep(e)
    return layers["INSIDE"], layers["OUTSIDE"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir", help="build directory (frame.json, strips.json, strips/*.dxf)")
    ap.add_argument("--min-overlap", type=float, default=25.0, help="minimum hub lap, mm (25)")
    ap.add_argument("--json", metavar="OUT", help="write the figures as JSON")
    ap.add_argument("--step", type=float, default=0.05, help="arc/line flattening step, mm (0.05)")
    a = ap.parse_args(argv)

    try:
        frame, strips = load_inputs(a.dir)
        units = frame["units"]
        links = frame["links"]
        cut = frame["params"]["cut"]
        neck_w, leg_w = float(cut["neck"]), float(cut["leg"])
        thickness = float(frame["params"]["thickness"])
        jl = frame["params"]["joint_limits"]
        bend_lim, twist_lim = float(jl["bend"]), float(jl["twist"])
    except InputError as e:
        print("fold_check: %s" % e, file=sys.stderr)
        return 2
    except (KeyError, TypeError) as e:
        print("fold_check: malformed frame.json: %r" % e, file=sys.stderr)
        return 2

    step = a.step
    K = max(1, int(round(3.0 / step)))       # coarse stride: ~3 mm
    thr = 0.5 * (neck_w + leg_w)               # web narrower than this = neck
    nu = len(units)
    uid = [u["id"] for u in units]

    flat_tile = [None] * nu
    hub_mot = [None] * nu
    pri_mot = [None] * nu
    hub_pins = [None] * nu   # flat, 4x2
    rim_pins = [None] * nu
    neck_folds = [None] * nu  # per leg: the hub neck's and the rim neck's fold line, flat
    slot_dense = [None] * nu  # the unit's cuts, flattened
    plate_flat = [None] * nu  # hub plate corners, flat
    cut_plate = [None] * nu   # primary plate as the outline cuts it: flat quad, side lines
    strip_of = [None] * nu
    bridges = []              # (where, span error mm, bend rad, twist rad)
    problems = []            # (check, where, message)
    kabsch_max = 0.0
    inner_violations = 0

    try:
        strip_list = strips["strips"]
    except (KeyError, TypeError) as e:
        print("fold_check: malformed strips.json: %r" % e, file=sys.stderr)
        return 2

    for st in strip_list:
        path = os.path.join(a.dir, "strips", "%s.dxf" % st["id"])
        try:
            slots, outside = read_cut(path)
        except InputError as e:
            print("fold_check: %s" % e, file=sys.stderr)
            return 2
        tiles = [(fl["unit"], np.array(fl["primary"], float)) for fl in st["flat"]]
        per_unit = {ui: [] for ui, _ in tiles}
        for s in slots:
            c = s[:, :2].mean(0)
            owner = [ui for ui, T in tiles if point_in_convex(T, c)]
            if len(owner) != 1:
                problems.append(("slots", st["id"], "slot at (%.1f, %.1f) in %d tiles"
                                 % (c[0], c[1], len(owner))))
                continue
            per_unit[owner[0]].append(s)
        for ui, T in tiles:
            u = units[ui]
            flat_tile[ui] = T
            hub_mot[ui] = kabsch_2d_to_3d(T, u["hub"])
            pri_mot[ui] = kabsch_2d_to_3d(T, u["primary"])
            kabsch_max = max(kabsch_max, hub_mot[ui][2], pri_mot[ui][2])
            sl = per_unit[ui]
            if len(sl) != 4:
                problems.append(("legs", uid[ui], "%d slots in the DXF (want 4)" % len(sl)))
                continue
            dense, lines, prims = [], [], []
            for s in sl:
                fd, ln, pr = flatten_lwpolyline(s, step)
                dense.append(fd)
                lines.append(ln)
                prims.append(pr)
            ctr = T.mean(0)
            # ---- necks: pairs of slots with two narrow webs
            cand = []
            for i in range(4):
                for k in range(i + 1, 4):
                    nk = necks_between(dense[i], dense[k], K, thr, prims[i], prims[k])
                    if len(nk) == 2:
                        cand.append(nk)
                    elif len(nk) != 0:
                        problems.append(("legs", uid[ui], "slots %d/%d: %d necks" % (i, k, len(nk))))
            hp = [None] * 4
            rp = [None] * 4
            folds = [None] * 4
            slot_dense[ui] = dense
            for nk in cand:
                best = None
                for j in range(4):
                    for h, r in ((nk[0], nk[1]), (nk[1], nk[0])):
                        cost = np.linalg.norm(h[1] - T[j]) + np.linalg.norm(r[1] - T[(j + 1) % 4])
                        if best is None or cost < best[0]:
                            best = (cost, j, h, r)
                _, j, h, r = best
                if hp[j] is not None:
                    problems.append(("legs", uid[ui], "two slot pairs claim leg %d" % j))
                hp[j], rp[j] = h[1], r[1]
                folds[j] = (h[3] - h[2], r[3] - r[2])
                # the leg joins the hub on the inner slot track and the rim on the
                # outer one: the hub neck lies deeper inside the tile (a leg width
                # and a slot), on any tile however skewed
                if depth_in(T, h[1]) <= depth_in(T, r[1]):
                    inner_violations += 1
                    problems.append(("legs", uid[ui], "leg %d hub neck not inner" % j))
            if any(x is None for x in hp):
                problems.append(("legs", uid[ui], "found %d of 4 legs" % sum(x is not None for x in hp)))
            else:
                hub_pins[ui] = np.array(hp)
                rim_pins[ui] = np.array(rp)
                neck_folds[ui] = folds
            # ---- hub plate: quad of the four inner slot edges.
            # The hub plate's corners are not cut as corners (the legs' hub
            # necks join there), so each corner is derived as the intersection
            # of the lines of the two adjacent inner slot edges: per slot the
            # long straight edge nearest the tile centre (longer than half a side:
            # the sides of a relief cut into the hub for a neighbour's leg are
            # shorter).
            side_len = np.linalg.norm(T[1] - T[0])
            side_n = []
            for j in range(4):
                dj = T[(j + 1) % 4] - T[j]
                nn = np.array([dj[1], -dj[0]]) / np.linalg.norm(dj)
                if np.dot(nn, 0.5 * (T[j] + T[(j + 1) % 4]) - ctr) < 0:
                    nn = -nn
                side_n.append(nn)
            edge_of_side = [None] * 4
            straight = [(p, q) for ln in lines for p, q in ln if np.linalg.norm(q - p) > 1.0]
            for j in range(4):
                dj = (T[(j + 1) % 4] - T[j]) / np.linalg.norm(T[(j + 1) % 4] - T[j])
                groups = []   # [offset, total length, longest edge]
                for p, q in straight:
                    e = (q - p) / np.linalg.norm(q - p)
                    if abs(e[0] * dj[1] - e[1] * dj[0]) > math.sin(math.radians(2.0)):
                        continue
                    off = float(np.dot(0.5 * (p + q) - ctr, side_n[j]))
                    if off <= 0:
                        continue
                    ln_ = float(np.linalg.norm(q - p))
                    for g in groups:
                        if abs(g[0] - off) < 0.2:
                            g[1] += ln_
                            if ln_ > np.linalg.norm(g[2][1] - g[2][0]):
                                g[2] = (p, q)
                            break
                    else:
                        groups.append([off, ln_, (p, q)])
                # the line nearest the centre that runs along most of the side (a relief
                # cut into the hub breaks it, and its own sides are short)
                long_ = [g for g in groups if g[1] >= 0.4 * side_len]
                if long_:
                    edge_of_side[j] = min(long_, key=lambda g: g[0])[2]
            if any(e is None for e in edge_of_side):
                problems.append(("laps", uid[ui], "hub plate edges not found"))
            else:
                pc = [line_intersect(edge_of_side[(j - 1) % 4], edge_of_side[j]) for j in range(4)]
                if any(c is None for c in pc):
                    problems.append(("laps", uid[ui], "hub plate edges parallel"))
                else:
                    plate_flat[ui] = np.array(pc)

        # ---- primary plates as cut, and the bridges that join them (checks 4 and 5)
        out_dense, out_lines = [], []
        for o in outside:
            fd, ln, _ = flatten_lwpolyline(o, step)
            out_dense.append(fd)
            out_lines.extend(ln)
        if not outside:
            problems.append(("plates", st["id"], "no OUTSIDE outline in the DXF"))
        for ui, T in tiles:
            strip_of[ui] = st["id"]
            cut_plate[ui] = plate_as_cut(T, out_lines)
            if cut_plate[ui] is None:
                problems.append(("plates", uid[ui], "primary plate edges not found in the outline"))
        flat_of = dict(tiles)
        for pin in st.get("pins", []):
            fa, fb = pin["units"]
            where = "%s~%s" % (uid[fa], uid[fb])
            if fa not in flat_of or fb not in flat_of or cut_plate[fa] is None or cut_plate[fb] is None:
                problems.append(("bridges", where, "bridged units not both in strip %s" % st["id"]))
                continue
            A, B = flat_of[fa], flat_of[fb]
            ka = int(np.argmin([np.linalg.norm(0.5 * (A[k] + A[(k + 1) % 4]) - B.mean(0)) for k in range(4)]))
            kb = int(np.argmin([np.linalg.norm(0.5 * (B[k] + B[(k + 1) % 4]) - A.mean(0)) for k in range(4)]))
            xs = crossings(A, ka, out_dense)
            if len(xs) != 2:
                problems.append(("bridges", where, "%d outline crossings of the joint (a bridge has 2)" % len(xs)))
                continue
            a0, d, _, _ = side_frame(A, ka)
            span = 0.0
            for u in xs:
                x = a0 + u * d
                pa = foot(cut_plate[fa][1][ka], x)
                pb = foot(cut_plate[fb][1][kb], x)
                span = max(span, abs(np.linalg.norm(apply(pri_mot[fa], pa) - apply(pri_mot[fb], pb))
                                     - np.linalg.norm(pa - pb)))
            bend, twist = turn(pri_mot[fa][0], pri_mot[fb][0], d)
            bridges.append((where, span, bend, twist))

    # ---------------------------------------------------------- check 1
    legs_checked = 0
    leg_err = (0.0, None)
    pin_off = (0.0, None)
    leg_fail = []
    pin_fail = []
    tool_leg_err = 0.0   # leg test with frame.json pins (informational)
    tool_len_err = 0.0   # |H-R| (ours) vs frame.json pins.length (informational)
    for ui in range(nu):
        if flat_tile[ui] is None:
            problems.append(("legs", uid[ui], "unit not in any strip"))
            continue
        if hub_pins[ui] is None:
            continue
        u = units[ui]
        fp = u.get("pins") or {}
        for j in range(4):
            h, r = hub_pins[ui][j], rim_pins[ui][j]
            H, R = apply(hub_mot[ui], h), apply(pri_mot[ui], r)
            err = abs(np.linalg.norm(H - R) - np.linalg.norm(h - r))
            legs_checked += 1
            where = "%s leg %d" % (uid[ui], j)
            if leg_err[1] is None or err > leg_err[0]:
                leg_err = (err, where)
            if err > LEG_TOL:
                leg_fail.append(where)
            try:
                off = max(np.linalg.norm(H - np.array(fp["hub"][j], float)),
                          np.linalg.norm(R - np.array(fp["rim"][j], float)))
            except (KeyError, IndexError, TypeError):
                off = float("inf")
            if pin_off[1] is None or off > pin_off[0]:
                pin_off = (off, where)
            if off > PIN_TOL:
                pin_fail.append(where)
            # informational: the same leg test with the tool's own pins
            try:
                Ht, Rt = np.array(fp["hub"][j], float), np.array(fp["rim"][j], float)
                ht = (hub_mot[ui][0].T @ (Ht - hub_mot[ui][1]))[:2]
                rt = (pri_mot[ui][0].T @ (Rt - pri_mot[ui][1]))[:2]
                tool_leg_err = max(tool_leg_err, abs(np.linalg.norm(Ht - Rt) - np.linalg.norm(ht - rt)))
                if "length" in fp:
                    tool_len_err = max(tool_len_err, abs(np.linalg.norm(H - R) - float(fp["length"][j])))
            except (KeyError, IndexError, TypeError, ValueError):
                pass

    # ---------------------------------------------------------- check 2
    hub_ctr = [np.mean(np.array(u["hub"], float), 0) for u in units]
    plate3 = [None if plate_flat[ui] is None else
              np.array([apply(hub_mot[ui], p) for p in plate_flat[ui]]) for ui in range(nu)]
    plate_dev = (0.0, None)
    for ui in range(nu):
        if plate3[ui] is not None and "hub_plate" in units[ui]:
            dv = float(np.max(np.linalg.norm(plate3[ui] - np.array(units[ui]["hub_plate"], float), axis=1)))
            if plate_dev[1] is None or dv > plate_dev[0]:
                plate_dev = (dv, uid[ui])
    laps_checked = 0
    lap_min = (float("inf"), None)
    lap_max = -float("inf")
    lap_claim = (0.0, None)
    lap_fail, claim_fail = [], []
    # one lap asked for every link (params.hub_lap): every lap within its tolerance of it
    one_lap_goal = frame["params"].get("hub_lap")
    one_lap = (0.0, None)
    one_lap_fail = []
    stack_lift = (0.0, None)  # hub plates at a lap: how far from one lying on the other
    stack_gap = (0.0, None)   # ... and the widest gap between them over the lap
    stack_closest = (0.0, None)   # ... and the closest they come over it
    stack_fail = []
    along_min = (float("inf"), None)  # the plates' overlap along the line of centres
    along_short = []
    along_none = 0
    leg_through = (0.0, None)  # a leg's centre line into the neighbour's hub plate at a lap
    legs_through = 0
    under_upper = (0.0, None)  # a cut (a relief) of the lower hub plate under the upper one
    slot_mismatch = 0
    gap_max = (-float("inf"), None)
    through_links = []
    gap_claim_err = 0.0
    welds = []               # (where, gap at the joint point, |gap - joint.gap|)
    reach = (0.0, None)      # deepest reach of one plate into another, between strips
    reach_fail = []
    rim_reach = (0.0, None)  # ... and of one plate into the next of its strip, across a bridge
    rim_fail = []
    for li, lk in enumerate(links):
        f, g = lk["units"]
        where = "%s~%s" % (uid[f], uid[g])
        if plate3[f] is None or plate3[g] is None:
            lap_fail.append(where)
            continue
        e = hub_ctr[g] - hub_ctr[f]
        e = e / np.linalg.norm(e)
        kf = int(np.argmin(np.linalg.norm(plate3[f] - hub_ctr[g], axis=1)))
        kg = int(np.argmin(np.linalg.norm(plate3[g] - hub_ctr[f], axis=1)))
        if "slots" in lk and list(lk["slots"]) != [kf, kg]:
            slot_mismatch += 1
        lap = float(np.dot(plate3[f][kf] - plate3[g][kg], e))
        laps_checked += 1
        lh = lap_heights(plate3[f], plate3[g])
        if lh is not None:
            # one slab on the other: 0; else the smaller move along the normal that makes it
            lo, hi = lh
            lift = max(0.0, min(thickness - lo, hi + thickness))
            if stack_lift[1] is None or lift > stack_lift[0]:
                stack_lift = (lift, where)
            if lift > REACH_TOL:
                stack_fail.append(where)
            # widest gap between the two over the lap (the wedge when not yet stacked)
            widest = hi - thickness if lo >= thickness else (-lo - thickness if hi <= -thickness else hi - lo)
            if stack_gap[1] is None or widest > stack_gap[0]:
                stack_gap = (widest, where)
            closest = lo - thickness if lo >= thickness else (-hi - thickness if hi <= -thickness else 0.0)
            if stack_closest[1] is None or closest > stack_closest[0]:
                stack_closest = (closest, where)
        # each leg leaves its hub at a corner, where the neighbour's hub plate laps: the
        # leg as a plate, its section through that plate, against the plate's steel (the
        # relief cut for it excepted)
        for u1, u2 in ((f, g), (g, f)):
            if hub_pins[u1] is None or plate3[u2] is None or slot_dense[u2] is None:
                continue
            upper_seen = False
            for j in range(4):
                leg = leg_plate(flat_tile[u1], cut, float(frame["params"]["cut"]["joint"]),
                                hub_pins[u1][j], rim_pins[u1][j], neck_folds[u1][j],
                                hub_mot[u1], pri_mot[u1], j)
                if leg is None:
                    continue
                sec = leg_section(leg, plate3[u2], hub_mot[u2], thickness)
                if len(sec) >= 3 and not upper_seen:
                    # u1's leg runs down through u2's plate: u1's plate is the upper one
                    upper_seen = True
                    R, tt = hub_mot[u2][0], hub_mot[u2][1]
                    up = [(R.T @ (X - tt))[:2] for X in plate3[u1]]
                    under = cut_under(up, plate_flat[u2], slot_dense[u2])
                    if under > under_upper[0] or under_upper[1] is None:
                        under_upper = (under, "%s under %s" % (uid[u2], uid[u1]))
                d_ = into_steel(sec, plate_flat[u2], slot_dense[u2])
                if d_ > leg_through[0] or leg_through[1] is None:
                    leg_through = (d_, "%s leg %d into %s" % (uid[u1], j, uid[u2]))
                if d_ > REACH_TOL:
                    legs_through += 1
        if lap < lap_min[0]:
            lap_min = (lap, where)
        lap_max = max(lap_max, lap)
        if lap < a.min_overlap:
            lap_fail.append(where)
        along = overlap_along(plate3[f], plate3[g])
        if along < along_min[0]:
            along_min = (along, where)
        if along < a.min_overlap:
            along_short.append(where)
        along_none += along <= 0.0
        if one_lap_goal:
            off = abs(lap - float(one_lap_goal["length"]))
            if one_lap[1] is None or off > one_lap[0]:
                one_lap = (off, where)
            if not off <= float(one_lap_goal["tolerance"]):
                one_lap_fail.append(where)
        ce = abs(lap - float(lk.get("hub_overlap", float("nan"))))
        if not ce <= LAP_CLAIM_TOL:
            claim_fail.append(where)
        if ce != ce:
            ce = float("inf")
        if lap_claim[1] is None or ce > lap_claim[0]:
            lap_claim = (ce, where)
        # ---- check 3 (informational): facing primary sides, 3D as in frame.json
        # (the primary motion maps the flat tile exactly onto `primary`, so the
        # moved sides are the frame.json sides).  Facing side = the side whose
        # midpoint lies furthest towards the neighbour; the gap is their segment
        # distance, negative when a facing side pierces the other primary plate
        # (the primaries pass through each other).  The claim comparison uses |gap|.
        Pf = np.array(units[f]["primary"], float)
        Pg = np.array(units[g]["primary"], float)
        ep = Pg.mean(0) - Pf.mean(0)
        sa = int(np.argmax([np.dot(0.5 * (Pf[j] + Pf[(j + 1) % 4]), ep) for j in range(4)]))
        sb = int(np.argmin([np.dot(0.5 * (Pg[j] + Pg[(j + 1) % 4]), ep) for j in range(4)]))
        pa_, pb_ = seg_seg(Pf[sa], Pf[(sa + 1) % 4], Pg[sb], Pg[(sb + 1) % 4])
        dd = float(np.linalg.norm(pb_ - pa_))

        # through each other: the facing side of one unit pierces the other's
        # primary plate (segment crosses the plate's plane inside the quad)
        through = dd < 1e-6 or seg_pierces_quad(Pg[sb], Pg[(sb + 1) % 4], Pf) \
            or seg_pierces_quad(Pf[sa], Pf[(sa + 1) % 4], Pg)
        gap = -dd if through else dd
        if through:
            through_links.append(where)
        claimed = float(lk.get("primary_gap", float("nan")))
        if claimed == claimed:
            gap_claim_err = max(gap_claim_err, abs(dd - claimed))
        if gap_max[1] is None or gap > gap_max[0]:
            gap_max = (gap, where)
        # ---- checks 5 and 6: neighbouring plates, as cut, thickness included
        if cut_plate[f] is None or cut_plate[g] is None:
            continue
        qf = np.array([apply(pri_mot[f], p) for p in cut_plate[f][0]])
        qg = np.array([apply(pri_mot[g], p) for p in cut_plate[g][0]])
        pf_, pg_ = plate_frame(qf), plate_frame(qg)
        # no plate reaches into its neighbour: the facing edge of each, all along; in one
        # strip across the bridge's joint slot (turned in their plane, the two rims meet at
        # the end of the side away from the bridge)
        deep = max(segment_reach(qg[sb], qg[(sb + 1) % 4], pf_, thickness),
                   segment_reach(qf[sa], qf[(sa + 1) % 4], pg_, thickness))
        if strip_of[f] == strip_of[g]:
            if rim_reach[1] is None or deep > rim_reach[0]:
                rim_reach = (deep, where)
            if deep > REACH_TOL:
                rim_fail.append(where)
            continue
        # welded at the joint point frame.json gives (links[].joint.along on f's facing
        # side), else where the facing edges come closest
        jt = lk.get("joint") or {}
        line = cut_plate[f][1][sa]
        T = flat_tile[f]
        if "along" in jt:
            s_ = float(jt["along"][0])
            w2 = foot(line, T[sa] + s_ * (T[(sa + 1) % 4] - T[sa]))
            wg = plate_gap(apply(pri_mot[f], w2), pg_, thickness)
        else:
            wg = min(plate_gap(x, pg_, thickness) for x in np.linspace(qf[sa], qf[(sa + 1) % 4], 65))
        ce = abs(wg - float(jt["gap"])) if "gap" in jt else float("inf")
        welds.append((where, wg, ce))
        if reach[1] is None or deep > reach[0]:
            reach = (deep, where)
        if deep > REACH_TOL:
            reach_fail.append(where)

    # ---------------------------------------------------------- check 4
    span_w = max(bridges, key=lambda b: b[1], default=(None, 0.0, 0.0, 0.0))
    bend_w = max(bridges, key=lambda b: abs(b[2]), default=(None, 0.0, 0.0, 0.0))
    twist_w = max(bridges, key=lambda b: abs(b[3]), default=(None, 0.0, 0.0, 0.0))
    bridge_fail = [b[0] for b in bridges
                   if b[1] > BRIDGE_TOL or abs(b[2]) > bend_lim or abs(b[3]) > twist_lim]
    weld_w = max(welds, key=lambda w: w[1], default=(None, 0.0, 0.0))
    weld_claim = max(welds, key=lambda w: w[2], default=(None, 0.0, 0.0))
    weld_fail = [w[0] for w in welds if w[1] > WELD_TOL]
    n_pins = sum(len(st.get("pins", [])) for st in strip_list)

    # ---------------------------------------------------------- report
    struct = [p for p in problems]
    rows = []

    def row(name, worst, limit, where, ok):
        rows.append((name, worst, limit, where, ok))

    row("leg length error (mm)", "%.3g" % leg_err[0], "<= %g" % LEG_TOL, leg_err[1] or "-",
        not leg_fail and legs_checked > 0)
    row("pin offset vs frame.json (mm)", "%.3g" % pin_off[0], "<= %g" % PIN_TOL, pin_off[1] or "-",
        not pin_fail and legs_checked > 0)
    row("hub lap min (mm)", "%.3f" % lap_min[0], ">= %g" % a.min_overlap, lap_min[1] or "-",
        not lap_fail and laps_checked > 0)
    if one_lap_goal:
        row("hub lap off the one lap asked (mm)", "%.3f" % one_lap[0],
            "<= %g" % float(one_lap_goal["tolerance"]), one_lap[1] or "-", not one_lap_fail)
    # the tips of a lap may pass each other offset sideways: the plates then overlap along
    # the line of centres by less than the lap, and a lap weld has only that to hold on to
    row("hub lap, the plates' overlap along the line of centres (mm)", "%.3f" % along_min[0],
        ">= %g" % a.min_overlap, along_min[1] or "-", not along_short and laps_checked > 0)
    row("hub lap vs claim (mm)", "%.3g" % lap_claim[0], "<= %g" % LAP_CLAIM_TOL, lap_claim[1] or "-",
        not claim_fail and laps_checked > 0)
    row("bridge span, folded - flat (mm)", "%.3g" % span_w[1], "<= %g" % BRIDGE_TOL, span_w[0] or "-",
        not [b for b in bridges if b[1] > BRIDGE_TOL] and len(bridges) == n_pins)
    row("bridge bent in its plane (deg)", "%.3g" % math.degrees(abs(bend_w[2])),
        "<= %.3g" % math.degrees(bend_lim), bend_w[0] or "-", abs(bend_w[2]) <= bend_lim)
    row("bridge twisted (deg)", "%.3g" % math.degrees(abs(twist_w[3])),
        "<= %.3g" % math.degrees(twist_lim), twist_w[0] or "-", abs(twist_w[3]) <= twist_lim)
    row("weld: plates of two strips apart (mm)", "%.3g" % weld_w[1], "<= %g" % WELD_TOL, weld_w[0] or "-",
        not weld_fail)
    row("weld gap vs links[].joint.gap (mm)", "%.3g" % weld_claim[2], "<= %g" % LAP_CLAIM_TOL,
        weld_claim[0] or "-", weld_claim[2] <= LAP_CLAIM_TOL)
    row("plates of two strips into each other (mm)", "%.3g" % reach[0], "<= %g" % REACH_TOL, reach[1] or "-",
        not reach_fail)
    row("bridge: plates into each other across the slot (mm)", "%.3g" % rim_reach[0],
        "<= %g" % REACH_TOL, rim_reach[1] or "-", not rim_fail)
    row("hub plates at a lap into each other (mm)", "%.3g" % stack_lift[0], "<= %g" % REACH_TOL,
        stack_lift[1] or "-", not stack_fail)
    if frame["params"].get("hub_laps_touch"):
        # the frame says every lap's plates were pulled together: they touch somewhere, as
        # close as a weld bridges
        row("hub plates at a lap, closest gap between them (mm)", "%.3f" % stack_closest[0],
            "<= %g" % WELD_TOL, stack_closest[1] or "-", stack_closest[0] <= WELD_TOL)
    row("DXF topology (slots/necks)", "%d problems" % len(struct), "0",
        (struct[0][1] if struct else "-"), not struct)
    row("kabsch residual (mm)", "%.3g" % kabsch_max, "<= %g" % KABSCH_TOL, "-", kabsch_max <= KABSCH_TOL)
    ok = all(r[4] for r in rows)
    w = [max(len(str(r[i])) for r in rows + [("check", "worst", "limit", "where", "ok")]) for i in range(4)]
    print("fold check of %s: %d units, %d strips, %d links" % (a.dir, nu, len(strip_list), len(links)))
    print("%-*s  %*s  %-*s  %-*s  %s" % (w[0], "check", w[1], "worst", w[2], "limit", w[3], "where", "ok"))
    for r in rows:
        print("%-*s  %*s  %-*s  %-*s  %s" % (w[0], r[0], w[1], r[1], w[2], r[2], w[3], r[3],
                                            "ok" if r[4] else "FAIL"))
    print("info: legs checked %d, laps checked %d, lap range %.3f .. %.3f mm"
          % (legs_checked, laps_checked, lap_min[0], lap_max))
    print("info: leg test with frame.json pins instead of ours: max %.3g mm; our |H-R| vs "
          "pins.length: max %.3g mm" % (tool_leg_err, tool_len_err))
    print("info: hub plate corners vs frame.json hub_plate: max %.3g mm (%s); links whose "
          "facing corners differ from links[].slots: %d" % (plate_dev[0], plate_dev[1], slot_mismatch))
    print("info: largest primary gap %.3f mm (%s) (vs links[].primary_gap: max diff %.3g mm); "
          "links with facing primary sides passing through each other: %d%s"
          % (gap_max[0], gap_max[1], gap_claim_err, len(through_links),
             (" (" + ", ".join(through_links[:5]) + ")") if through_links else ""))
    print("info: hub plates at their laps: widest gap between the two over a lap %.3f mm (%s)"
          % (stack_gap[0], stack_gap[1]))
    print("info: hub plates at their laps: closest gap between the two over a lap, largest %.3f mm (%s)"
          % (stack_closest[0], stack_closest[1]))
    print("info: hub plates at their laps: overlap along the line of centres, smallest %.3f mm (%s); "
          "%d laps under %g mm, %d not overlapping at all"
          % (along_min[0], along_min[1], len(along_short), a.min_overlap, along_none))
    print("legs through a neighbour's hub plate outside its relief: %d, deepest %.3g mm (%s)"
          % (legs_through, leg_through[0], leg_through[1]))
    print("info: reliefs under the hub plate lying on theirs at a lap: deepest %.3g mm (%s)"
          % (under_upper[0], under_upper[1]))
    # legs against the rims of the units round their tile's corners (the e2e tests hold it
    # where the joints close)
    leg_rim = (0.0, None)
    legs_into_rims = 0
    faces = frame["mesh"]["faces"]
    around = {}
    for ui, fc in enumerate(faces):
        for vtx in fc:
            around.setdefault(vtx, []).append(ui)
    for u1 in range(nu):
        if hub_pins[u1] is None or neck_folds[u1] is None or u1 >= len(faces):
            continue
        near = sorted(set(w for vtx in faces[u1] for w in around[vtx]) - {u1})
        for j in range(4):
            leg = leg_plate(flat_tile[u1], cut, float(cut["joint"]), hub_pins[u1][j],
                            rim_pins[u1][j], neck_folds[u1][j], hub_mot[u1], pri_mot[u1], j)
            if leg is None:
                continue
            for w in near:
                if cut_plate[w] is None:
                    continue
                qw = np.array([apply(pri_mot[w], p) for p in cut_plate[w][0]])
                d_ = rim_reach_of(leg, qw, float(cut["rim"]), thickness)
                if d_ > leg_rim[0] or leg_rim[1] is None:
                    leg_rim = (d_, "%s leg %d into %s" % (uid[u1], j, uid[w]))
                if d_ > REACH_TOL:
                    legs_into_rims += 1
    print("legs into a neighbour's rim: %d, deepest %.3g mm (%s)"
          % (legs_into_rims, leg_rim[0], leg_rim[1]))
    # a leg through steel fails the check as a collision of plates does
    for name, n in (("legs through a neighbour's hub plate outside its relief", legs_through),
                    ("legs into a neighbour's rim", legs_into_rims)):
        if n:
            ok = False
            print("FAIL %s: %d" % (name, n))
    for name, lst in (("leg length", leg_fail), ("pin offset", pin_fail),
                      ("hub lap", lap_fail), ("lap claim", claim_fail),
                      ("hub lap off the one lap asked", one_lap_fail), ("bridge", bridge_fail),
                      ("weld", weld_fail), ("plates into each other", reach_fail),
                      ("plates across a bridge's slot", rim_fail),
                      ("hub plates into each other", stack_fail)):
        if lst:
            print("FAIL %s: %d: %s%s" % (name, len(lst), ", ".join(lst[:10]), " ..." if len(lst) > 10 else ""))
    for p in struct[:10]:
        print("FAIL %s: %s: %s" % p)

    if a.json:
        out = {
            "legs_checked": legs_checked,
            "leg_error_max": leg_err[0],
            "pin_offset_max": pin_off[0],
            "laps_checked": laps_checked,
            "lap_min": lap_min[0] if laps_checked else None,
            "lap_max": lap_max if laps_checked else None,
            "lap_claim_error_max": lap_claim[0],
            "lap_off_one_length_max": one_lap[0] if one_lap_goal else None,
            "hub_plate_offset_max": plate_dev[0],
            "leg_error_tool_pins_max": tool_leg_err,
            "leg_length_claim_error_max": tool_len_err,
            "kabsch_residual_max": kabsch_max,
            "primary_gap_max": gap_max[0] if gap_max[1] else None,
            "primary_crossings": len(through_links),
            "primary_gap_claim_error_max": gap_claim_err,
            "bridges_checked": len(bridges),
            "bridges_in_strips": n_pins,
            "bridge_span_max": span_w[1],
            "bridge_bend_max_deg": math.degrees(abs(bend_w[2])),
            "bridge_twist_max_deg": math.degrees(abs(twist_w[3])),
            "bridge_bend_limit_deg": math.degrees(bend_lim),
            "bridge_twist_limit_deg": math.degrees(twist_lim),
            "welds_checked": len(welds),
            "weld_gap_max": weld_w[1],
            "weld_claim_error_max": weld_claim[2],
            "reach_max": reach[0],
            "bridge_reach_max": rim_reach[0],
            "hub_stack_lift_max": stack_lift[0],
            "hub_stack_gap_max": stack_gap[0],
            "hub_stack_closest_max": stack_closest[0],
            "lap_overlap_along_min": along_min[0] if laps_checked else None,
            "laps_overlap_along_short": len(along_short),
            "laps_overlap_along_none": along_none,
            "legs_through_hub_plates": legs_through,
            "leg_through_hub_plate_max": leg_through[0],
            "relief_under_upper_max": under_upper[0],
            "legs_into_rims": legs_into_rims,
            "leg_into_rim_max": leg_rim[0],
            "problems": ["%s: %s: %s" % p for p in struct],
            "failing": {"leg": leg_fail, "pin": pin_fail, "lap": lap_fail, "lap_claim": claim_fail,
                        "one_lap": one_lap_fail,
                        "bridge": bridge_fail, "weld": weld_fail, "reach": reach_fail,
                        "bridge_reach": rim_fail,
                        "hub_stack": stack_fail},
            "ok": bool(ok),
            "worst": {"leg_error": leg_err[1], "pin_offset": pin_off[1],
                      "lap_min": lap_min[1], "lap_claim_error": lap_claim[1],
                      "bridge_span": span_w[0], "weld_gap": weld_w[0], "reach": reach[1]},
        }
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
