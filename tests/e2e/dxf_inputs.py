"""DXF parts written by ezdxf (not by spinvalence) the ways CAD programs write them, for
`tests/e2e/dxf_inputs.rs`. Usage: python3 dxf_inputs.py OUT_DIR [N_MANY]

Writes one file per case into OUT_DIR and OUT_DIR/cases.json: per case the file, what the
reader must do ("parts", or "refuse" with a word of the one-line error), what it must
report (words of its notes), and per expected part the exact area (mm^2), the hole count
and points on the outline and on each hole in the file's coordinates scaled to mm, so
that the test can check a placed part on the sheet against them (a mirrored or misread
part puts the points off its contours).
"""
import json
import math
import sys

import ezdxf
from ezdxf.math import OCS

OUT = sys.argv[1]
MANY = int(sys.argv[2]) if len(sys.argv) > 2 else 2000


def arc_points(a, b, bulge, n=24):
    """Points from a to b (excluded) along the bulge arc (a straight line for bulge 0)."""
    if abs(bulge) < 1e-12:
        return [a]
    sweep = 4 * math.atan(bulge)
    chord = math.dist(a, b)
    r = chord / (2 * abs(math.sin(sweep / 2)))
    mx, my = (a[0] + b[0]) / 2, (a[1] + b[1]) / 2
    d = r * math.cos(sweep / 2) * math.copysign(1, sweep)
    nx, ny = -(b[1] - a[1]) / chord, (b[0] - a[0]) / chord
    cx, cy = mx + nx * d, my + ny * d
    a0 = math.atan2(a[1] - cy, a[0] - cx)
    return [(cx + r * math.cos(a0 + sweep * k / n), cy + r * math.sin(a0 + sweep * k / n)) for k in range(n)]


def loop_points(verts):
    """Dense points of a closed loop of (x, y, bulge) vertices."""
    pts = []
    for i, (x, y, b) in enumerate(verts):
        nxt = verts[(i + 1) % len(verts)]
        a, c = (x, y), (nxt[0], nxt[1])
        seg = arc_points(a, c, b)
        # straight edges get points along them too
        if abs(b) < 1e-12:
            seg = [(a[0] + (c[0] - a[0]) * k / 8, a[1] + (c[1] - a[1]) * k / 8) for k in range(8)]
        pts.extend(seg)
    return pts


def shoelace(pts):
    return abs(sum(p[0] * q[1] - q[0] * p[1] for p, q in zip(pts, pts[1:] + pts[:1]))) / 2


def bulge_area(verts):
    """Exact area of a closed loop with bulges: polygon plus circular segments."""
    poly = shoelace([(v[0], v[1]) for v in verts])
    signed = sum(v[0] * w[1] - w[0] * v[1] for v, w in zip(verts, verts[1:] + verts[:1])) / 2
    orient = 1 if signed >= 0 else -1
    extra = 0.0
    for i, (x, y, b) in enumerate(verts):
        if abs(b) < 1e-12:
            continue
        nxt = verts[(i + 1) % len(verts)]
        chord = math.dist((x, y), nxt[:2])
        sweep = 4 * math.atan(b)
        r = chord / (2 * abs(math.sin(sweep / 2)))
        seg = r * r / 2 * (abs(sweep) - math.sin(abs(sweep)))
        extra += seg if (b > 0) == (orient > 0) else -seg
    return poly + extra


class Affine:
    """p -> M p + t, for the expected geometry of INSERTs and OCS."""

    def __init__(self, m=(1, 0, 0, 1), t=(0, 0)):
        self.m, self.t = m, t

    def __call__(self, p):
        a, b, c, d = self.m
        return (a * p[0] + b * p[1] + self.t[0], c * p[0] + d * p[1] + self.t[1])

    def then(self, o):
        a, b, c, d = self.m
        e, f, g, h = o.m
        return Affine((a * e + b * g, a * f + b * h, c * e + d * g, c * f + d * h), self(o.t))

    def det(self):
        a, b, c, d = self.m
        return a * d - b * c


def rot(deg):
    s, c = math.sin(math.radians(deg)), math.cos(math.radians(deg))
    return Affine((c, -s, s, c))


def move(x, y):
    return Affine(t=(x, y))


def scale(sx, sy=None):
    return Affine((sx, 0, 0, sy if sy is not None else sx))


# The test part: asymmetric (a mirror image is not the same part turned), 160 x 80 mm with
# a half-round right end, a chamfered top-left corner, a round hole and a slot, both off
# centre. Loops as (x, y, bulge), outline counter-clockwise.
OUTLINE = [(0, 0, 0), (160, 0, 1), (160, 80, 0), (25, 80, 0), (0, 55, 0)]
HOLE = (45, 30, 9)  # centre x, y, radius
SLOT = [(90, 50, 0), (130, 50, -1), (130, 62, 0), (90, 62, -1)]


def part_area():
    return bulge_area(OUTLINE) - math.pi * HOLE[2] ** 2 - bulge_area(SLOT)


def expected(xf=Affine(), units=1.0, outline=OUTLINE, holes=None, area=None):
    """The expected part: area and points, mapped by xf then scaled to mm."""
    if holes is None:
        circle = [(HOLE[0] + HOLE[2], HOLE[1], 1), (HOLE[0] - HOLE[2], HOLE[1], 1)]
        holes = [circle, SLOT]
    mm = lambda p: (p[0] * units, p[1] * units)
    if area is None:
        area = bulge_area(outline) - sum(bulge_area(h) for h in holes)
    return {
        "area": abs(xf.det()) * units * units * area,
        "holes": len(holes),
        "outline": [mm(xf(p)) for p in loop_points(outline)],
        "hole_points": [[mm(xf(p)) for p in loop_points(h)] for h in holes],
    }


def lw(msp, verts, layer="0", **attribs):
    msp.add_lwpolyline([(x, y, 0, 0, b) for x, y, b in verts], format="xyseb", close=True, dxfattribs={"layer": layer, **attribs})


def chain(msp, verts, layer="0", gap=0.0, extrusion=None):
    """The loop as LINE and ARC entities (ARC as CCW from start to end angles); `gap`
    shortens every piece at its end; `extrusion` (0, 0, -1) writes arcs in a mirrored OCS."""
    for i, (x, y, b) in enumerate(verts):
        nx, ny, _ = verts[(i + 1) % len(verts)]
        a, c = (x, y), (nx, ny)
        length = math.dist(a, c)
        if abs(b) < 1e-12:
            u = ((c[0] - a[0]) / length, (c[1] - a[1]) / length)
            msp.add_line(a, (c[0] - u[0] * gap, c[1] - u[1] * gap), dxfattribs={"layer": layer})
            continue
        sweep = 4 * math.atan(b)
        r = length / (2 * abs(math.sin(sweep / 2)))
        mx, my = (a[0] + c[0]) / 2, (a[1] + c[1]) / 2
        d = r * math.cos(sweep / 2) * math.copysign(1, sweep)
        cx, cy = mx - (c[1] - a[1]) / length * d, my + (c[0] - a[0]) / length * d
        t0 = math.degrees(math.atan2(a[1] - cy, a[0] - cx))
        t1 = math.degrees(math.atan2(c[1] - cy, c[0] - cx))
        dg = math.degrees(gap / r)
        start, end = (t0, t1 - dg) if sweep > 0 else (t1 + dg, t0)
        if extrusion is None:
            msp.add_arc((cx, cy), r, start, end, dxfattribs={"layer": layer})
        else:
            # in the OCS of (0, 0, -1) x runs the other way, and so do the angles
            ocs = OCS(extrusion)
            centre = ocs.from_wcs((cx, cy, 0))
            msp.add_arc(centre, r, 180 - end, 180 - start, dxfattribs={"layer": layer, "extrusion": extrusion})


def holes(msp, layer="0", extrusion=None):
    if extrusion is None:
        msp.add_circle(HOLE[:2], HOLE[2], dxfattribs={"layer": layer})
    else:
        ocs = OCS(extrusion)
        msp.add_circle(ocs.from_wcs((HOLE[0], HOLE[1], 0)), HOLE[2], dxfattribs={"layer": layer, "extrusion": extrusion})
    lw(msp, SLOT, layer)


def new(version="R2018", units=4):
    # setup: the standard line types (DASHED, CENTER, ...) in the table
    doc = ezdxf.new(version, setup=True)
    if version != "R12":
        doc.header["$INSUNITS"] = units
    return doc


cases = []


def case(name, doc, parts=None, notes=(), refuse=None, alone=False):
    doc.saveas(f"{OUT}/{name}.dxf")
    entry = {"file": f"{name}.dxf", "notes": list(notes), "alone": alone}
    if refuse:
        entry.update(expect="refuse", message=refuse)
    else:
        entry.update(expect="parts", parts=parts)
    cases.append(entry)


# LINE + ARC chains, CIRCLE holes
doc = new()
chain(doc.modelspace(), OUTLINE)
holes(doc.modelspace())
case("line_arc_chain", doc, [expected()])

# LWPOLYLINE with bulges and CIRCLE holes, the outline clockwise as some exporters write it
doc = new()
msp = doc.modelspace()
lw(msp, [OUTLINE[0]] + [(v[0], v[1], -OUTLINE[(i - 1) % 5][2]) for i, v in list(enumerate(OUTLINE))[:0:-1]])
holes(msp)
case("lwpolyline_clockwise", doc, [expected()])

# POLYLINE / VERTEX with bulges, R12 (no $INSUNITS in R12: read as mm)
doc = new("R12")
msp = doc.modelspace()
msp.add_polyline2d([(x, y, b) for x, y, b in OUTLINE], format="xyb", close=True)
msp.add_circle(HOLE[:2], HOLE[2])
msp.add_polyline2d([(x, y, b) for x, y, b in SLOT], format="xyb", close=True)
case("polyline_r12", doc, [expected()], notes=["no drawing units"])

# the same in R2018 as LINE/ARC on layer 0
doc = new("R2018")
chain(doc.modelspace(), OUTLINE)
holes(doc.modelspace())
case("chain_r2018", doc, [expected()])

# INSERT: rotated and scaled, nested (with a mirror), and arrays
doc = new()
plate = doc.blocks.new("PLATE", base_point=(10, 5))
lw(plate, OUTLINE)
holes(plate)
pair = doc.blocks.new("PAIR")
pair.add_blockref("PLATE", (0, 0), dxfattribs={"rotation": 90})
pair.add_blockref("PLATE", (300, 0), dxfattribs={"xscale": -1})
msp = doc.modelspace()
msp.add_blockref("PLATE", (0, 0), dxfattribs={"rotation": 30, "xscale": 1.5, "yscale": 1.5})
msp.add_blockref("PAIR", (600, 0), dxfattribs={"rotation": 45})
grid = msp.add_blockref("PLATE", (0, 600), dxfattribs={"rotation": 10})
grid.dxf.column_count, grid.dxf.row_count = 3, 2
grid.dxf.column_spacing, grid.dxf.row_spacing = 220, 150
base = move(-10, -5)
want = [expected(move(0, 0).then(rot(30)).then(scale(1.5)).then(base))]
outer = move(600, 0).then(rot(45))
want.append(expected(outer.then(rot(90)).then(base)))
want.append(expected(outer.then(move(300, 0)).then(scale(-1, 1)).then(base)))
for r in range(2):
    for c in range(3):
        off = rot(10)((c * 220, r * 150))
        want.append(expected(move(off[0], off[1] + 600).then(rot(10)).then(base)))
case("insert_blocks", doc, want)


# SPLINE and ELLIPSE outlines and holes
def spline_outline(msp, layer="0"):
    # a closed periodic-looking cubic B-spline through a control polygon: the outline
    pts = [(0, 0, 0), (80, -20, 0), (160, 0, 0), (180, 60, 0), (120, 110, 0), (40, 100, 0), (-20, 60, 0)]
    return closed_spline(msp, pts, layer)


def closed_spline(msp, pts, layer="0"):
    s = msp.add_spline(dxfattribs={"layer": layer})
    s.set_closed([p if len(p) == 3 else (p[0], p[1], 0) for p in pts], degree=3)
    return s


doc = new()
msp = doc.modelspace()
sp = spline_outline(msp)
msp.add_ellipse((80, 45), major_axis=(30, 10), ratio=0.5)
# the curve by ezdxf's B-spline evaluation (its path flattening of a closed spline is not
# the same curve in ezdxf 1.4)
spline_points = lambda s, n=2000: [(v.x, v.y) for v in s.construction_tool().approximate(n)][:-1]
outline_pts = spline_points(sp)
ell_pts = [(80 + 30 * math.cos(t) - 0.5 * 10 * math.sin(t), 45 + 10 * math.cos(t) + 0.5 * 30 * math.sin(t)) for t in [k * math.tau / 400 for k in range(400)]]
area = shoelace(outline_pts) - math.pi * math.hypot(30, 10) ** 2 * 0.5
part = {"area": area, "holes": 1, "outline": outline_pts[::10], "hole_points": [ell_pts]}
# an ELLIPSE outline with a SPLINE hole (a small closed spline)
msp.add_ellipse((400, 50), major_axis=(90, 0), ratio=0.6)
hole = closed_spline(msp, [(380, 40), (400, 30), (420, 40), (420, 60), (400, 70), (380, 60)])
hole_pts = spline_points(hole)
e2 = [(400 + 90 * math.cos(t), 50 + 54 * math.sin(t)) for t in [k * math.tau / 400 for k in range(400)]]
part2 = {"area": math.pi * 90 * 54 - shoelace(hole_pts), "holes": 1, "outline": e2, "hole_points": [hole_pts[::5]]}
case("spline_ellipse", doc, [part, part2], notes=["SPLINE fitted by arcs", "ELLIPSE fitted by arcs"])

# units: inches, metres, none
for name, code, unit in [("inches", 1, 25.4), ("metres", 6, 1000.0)]:
    doc = new(units=code)
    u = 1.0 / unit
    msp = doc.modelspace()
    lw(msp, [(x * u, y * u, b) for x, y, b in OUTLINE])
    msp.add_circle((HOLE[0] * u, HOLE[1] * u), HOLE[2] * u)
    lw(msp, [(x * u, y * u, b) for x, y, b in SLOT])
    case(f"units_{name}", doc, [expected(scale(u), unit)], notes=[f"scaled by {unit:g}"])
doc = new(units=0)
lw(doc.modelspace(), OUTLINE)
holes(doc.modelspace())
case("units_none", doc, [expected()], notes=["no drawing units"])

# mirrored extrusion (0, 0, -1) on ARC, CIRCLE and LWPOLYLINE, as ODA-based exporters write
doc = new()
msp = doc.modelspace()
chain(msp, OUTLINE, extrusion=(0, 0, -1))
holes(msp, extrusion=(0, 0, -1))
case("extrusion_arc_circle", doc, [expected()])
doc = new()
msp = doc.modelspace()
ocs = OCS((0, 0, -1))
# an LWPOLYLINE in that OCS: x negated, and the bulges with it
verts = [(-x, y, -b) for x, y, b in OUTLINE]
msp.add_lwpolyline([(x, y, 0, 0, b) for x, y, b in verts], format="xyseb", close=True, dxfattribs={"extrusion": (0, 0, -1)})
holes(msp, extrusion=(0, 0, -1))
case("extrusion_lwpolyline", doc, [expected()])

# duplicates: the outline drawn twice, a hole drawn twice, and repeated lines in a chain
doc = new()
msp = doc.modelspace()
lw(msp, OUTLINE)
lw(msp, OUTLINE)
holes(msp)
msp.add_circle(HOLE[:2], HOLE[2])
case("duplicate_outline", doc, [expected()], notes=["drawn twice"])
doc = new()
msp = doc.modelspace()
chain(msp, OUTLINE)
msp.add_line((0, 0), (100, 0))  # a repeat of part of the bottom edge
msp.add_line((160, 80), (60, 80))  # and of part of the top edge, the other way
holes(msp)
case("duplicate_lines", doc, [expected()], notes=["repeated or overlapping segments merged"])

# 0.01 mm gaps between every LINE and ARC
doc = new()
chain(doc.modelspace(), OUTLINE, gap=0.01)
holes(doc.modelspace())
case("gaps_0_01mm", doc, [expected()], notes=["gap of 0.0100 mm closed"])

# bend lines: a flat pattern 300 x 100 whose outline is split where two bend lines meet it
BENT = [(0, 0, 0), (100, 0, 0), (200, 0, 0), (300, 0, 0), (300, 100, 0), (200, 100, 0), (100, 100, 0), (0, 70, 0)]
for name, layer, linetype in [("bend_layer", "BEND", None), ("bend_on_layer_0", "0", None), ("bend_dashed", "0", "DASHED")]:
    doc = new()
    msp = doc.modelspace()
    chain(msp, BENT)
    attribs = {"layer": layer}
    if linetype:
        attribs["linetype"] = linetype
    for x in (100, 200):
        msp.add_line((x, 0), (x, 100), dxfattribs=attribs)
    msp.add_circle((50, 40), 10)
    circle = [(60, 40, 1), (40, 40, 1)]
    note = {"bend_layer": "bend lines", "bend_on_layer_0": "bend or construction lines", "bend_dashed": "dashed line type"}[name]
    case(name, doc, [expected(outline=BENT, holes=[circle])], notes=[note])

# a drawing border with a title block (lines and text) around a part, all on layer 0
doc = new()
msp = doc.modelspace()
msp.add_lwpolyline([(-50, -50), (400, -50), (400, 250), (-50, 250)], close=True)
msp.add_line((250, -50), (250, 0))
msp.add_line((250, 0), (400, 0))
msp.add_text("PART 42  SCALE 1:1", dxfattribs={"height": 5, "insert": (260, -30)})
lw(msp, OUTLINE)
holes(msp)
case("drawing_border", doc, [expected()], notes=["drawing border"])

# layer 0 beside the shop layers: one part on OUTSIDE / INSIDE, one on layer 0
doc = new()
msp = doc.modelspace()
lw(msp, OUTLINE, "OUTSIDE")
msp.add_circle(HOLE[:2], HOLE[2], dxfattribs={"layer": "INSIDE"})
lw(msp, SLOT, "INSIDE")
shift = move(0, 200)
lw(msp, [(x, y + 200, b) for x, y, b in OUTLINE])
msp.add_circle((HOLE[0], HOLE[1] + 200), HOLE[2])
lw(msp, [(x, y + 200, b) for x, y, b in SLOT])
case("layer0_beside_shop_layers", doc, [expected(), expected(shift)])

# several parts per file (turned, on layer 0)
doc = new()
msp = doc.modelspace()
want = []
for k in range(5):
    xf = move(250 * k, 0).then(rot(17 * k))
    lw(msp, [xf(v[:2]) + (v[2],) for v in OUTLINE])
    c = xf(HOLE[:2])
    msp.add_circle(c, HOLE[2])
    lw(msp, [xf(v[:2]) + (v[2],) for v in SLOT])
    want.append(expected(xf))
case("several_parts", doc, want)

# refusals: units the DXF reference does not define; a gap far beyond the join tolerance
doc = new(units=4)
doc.header["$INSUNITS"] = 99
lw(doc.modelspace(), OUTLINE)
case("units_unknown", doc, refuse="$INSUNITS 99", alone=True)
doc = new()
chain(doc.modelspace(), OUTLINE, gap=0.5)
case("gap_0_5mm", doc, refuse="open contour", alone=True)

# many small parts in one file: plates 40 x 25 with a hole, on a grid
doc = new()
msp = doc.modelspace()
small = [(0, 0, 0), (40, 0, 0), (40, 25, 0), (8, 25, 0), (0, 17, 0)]
want = []
side = math.ceil(math.sqrt(MANY))
for k in range(MANY):
    x, y = 60 * (k % side), 40 * (k // side)
    msp.add_lwpolyline([(x + a, y + b) for a, b, _ in small], close=True)
    msp.add_circle((x + 12, y + 10), 4)
    want.append({
        "area": bulge_area(small) - math.pi * 16,
        "holes": 1,
        "outline": [(x + p[0], y + p[1]) for p in loop_points(small)],
        "hole_points": [[(x + 12 + 4 * math.cos(t), y + 10 + 4 * math.sin(t)) for t in [j * math.tau / 16 for j in range(16)]]],
    })
case("many_parts", doc, want, alone=True)

with open(f"{OUT}/cases.json", "w") as f:
    json.dump({"cases": cases}, f)
print(f"wrote {len(cases)} cases")
