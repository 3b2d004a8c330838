"""Open every DXF given on the command line with ezdxf, run its auditor and fail on errors.

Also checks what the shop relies on: R2000, $INSUNITS = 4 (mm), the four layers, closed
LWPOLYLINEs on OUTSIDE/INSIDE, and INFO never plotted. With `--sheets` first, the files are
nested sheets: one or more outlines, a POINT (pierce point) on INFO per cut contour and a
TEXT label on INFO per part plus the sheet title.
"""
import sys

import ezdxf


def check(path, sheets):
    problems = []
    doc = ezdxf.readfile(path)
    auditor = doc.audit()
    for e in auditor.errors:
        problems.append(f"audit error: {e.message}")
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
    if len(msp.query('LWPOLYLINE[layer=="ETCH"]')) == 0:
        problems.append("nothing to etch")
    if not any(b != 0 for e in inside for (_, _, _, _, b) in e.get_points()):
        problems.append("no arcs in the cuts")
    return problems


def main():
    failed = False
    args = sys.argv[1:]
    sheets = bool(args) and args[0] == "--sheets"
    if sheets:
        args = args[1:]
    for path in args:
        problems = check(path, sheets)
        for p in problems:
            print(f"{path}: {p}")
        failed |= bool(problems)
    print(f"audited {len(args)} file(s)")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
