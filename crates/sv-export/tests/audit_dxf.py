"""Open every DXF given on the command line with ezdxf, run its auditor and fail on any
error or fix.

Also checks what the shop relies on (docs/dxf.md): R2000, $INSUNITS = 4 (mm), the four
layers, closed LWPOLYLINEs on OUTSIDE/INSIDE, INFO never plotted, every entity (TEXT
included, by ezdxf's own measure) inside the header extents, outside contours clockwise
and inside ones counter-clockwise, and all etching before the first cut. With `--sheets`
first, the files are nested sheets: one or more outlines, a POINT (pierce point) on INFO
per cut contour and a TEXT label on INFO per part plus the sheet title.
"""
import sys

import ezdxf
import ezdxf.path
from ezdxf import bbox


def check(path, sheets, strips_etched=True):
    problems = []
    doc = ezdxf.readfile(path)
    auditor = doc.audit()
    for e in auditor.errors:
        problems.append(f"audit error: {e.message}")
    for e in auditor.fixes:
        problems.append(f"audit fix: {e.message}")
    if doc.dxfversion != "AC1015":
        problems.append(f"version {doc.dxfversion}, expected AC1015")
    if doc.header.get("$INSUNITS") != 4:
        problems.append(f"$INSUNITS = {doc.header.get('$INSUNITS')}, expected 4")
    for name in ("OUTSIDE", "INSIDE", "ETCH", "INFO"):
        if name not in doc.layers:
            problems.append(f"layer {name} missing")
    if "INFO" in doc.layers and doc.layers.get("INFO").dxf.plot != 0:
        problems.append("layer INFO is plotted")
    msp = doc.modelspace()
    outside = msp.query('LWPOLYLINE[layer=="OUTSIDE"]')
    inside = msp.query('LWPOLYLINE[layer=="INSIDE"]')
    if sheets:
        if len(outside) < 1:
            problems.append("no outlines on the sheet")
        points = msp.query('POINT[layer=="INFO"]')
        if len(points) != len(outside) + len(inside):
            problems.append(f"{len(points)} pierce points for {len(outside) + len(inside)} contours")
        texts = msp.query('TEXT[layer=="INFO"]')
        if len(texts) < len(outside) + 1:
            problems.append(f"{len(texts)} labels for {len(outside)} parts and the title")
    elif len(outside) != 1:
        problems.append(f"{len(outside)} outlines, expected 1")
    for e in list(outside) + list(inside):
        if not e.closed:
            problems.append(f"open contour {e.dxf.handle} on {e.dxf.layer}")
    # cut direction: the sign of the area, arcs included (ezdxf's own flattening)
    for e, want in [(e, -1) for e in outside] + [(e, 1) for e in inside]:
        pts = [(p.x, p.y) for p in ezdxf.path.make_path(e).flattening(0.01)]
        area = sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(pts, pts[1:] + pts[:1])) / 2
        if area * want <= 0:
            which = "clockwise" if want < 0 else "counter-clockwise"
            problems.append(f"{e.dxf.layer} contour {e.dxf.handle} does not run {which}")
    # file order: every etched entity before the first cut contour
    kinds = [e.dxf.layer for e in msp if e.dxf.layer in ("OUTSIDE", "INSIDE", "ETCH")]
    if "ETCH" in kinds and ("OUTSIDE" in kinds or "INSIDE" in kinds):
        first_cut = min(i for i, k in enumerate(kinds) if k != "ETCH")
        if any(k == "ETCH" for k in kinds[first_cut:]):
            problems.append("etching after a cut in file order")
    # every entity inside the header extents (TEXT by ezdxf's font measure)
    lo, hi = doc.header.get("$EXTMIN"), doc.header.get("$EXTMAX")
    box = bbox.extents(msp)
    if box.has_data:
        tol = 1e-6
        if box.extmin.x < lo[0] - tol or box.extmin.y < lo[1] - tol or box.extmax.x > hi[0] + tol or box.extmax.y > hi[1] + tol:
            problems.append(f"entities {box.extmin} .. {box.extmax} outside the header extents {lo} .. {hi}")
    if strips_etched:
        if len(msp.query('LWPOLYLINE[layer=="ETCH"]')) == 0:
            problems.append("nothing to etch")
        if not any(b != 0 for e in inside for (_, _, _, _, b) in e.get_points()):
            problems.append("no arcs in the cuts")
    return problems


def main():
    failed = False
    args = sys.argv[1:]
    # --foreign-sheets: sheets of any parts (not our strips: maybe nothing etched, no arcs)
    foreign = bool(args) and args[0] == "--foreign-sheets"
    sheets = foreign or (bool(args) and args[0] == "--sheets")
    if sheets:
        args = args[1:]
    for path in args:
        problems = check(path, sheets, not foreign)
        for p in problems:
            print(f"{path}: {p}")
        failed |= bool(problems)
    print(f"audited {len(args)} file(s)")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
