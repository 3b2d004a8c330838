#!/usr/bin/env python3
"""Write benchmark hub meshes as OBJ quad meshes (mm, 1-based, faces counter-clockwise).

The formulas are those of sv_frame::QuadMesh::sphere_cap and QuadMesh::translational, so a
mesh written here is the mesh the Rust constructors build (up to the last bit of libm).

usage: make_meshes.py cap NX NY RADIUS SPACING OUT.obj
       make_meshes.py saddle NX NY SPACING R OUT.obj      # z = x^2/(2R) - y^2/(2R)
       make_meshes.py dome LX LY R1 R2 N OUT.obj          # a target (triangles), below
       make_meshes.py wave_oval A B N OUT.obj             # a target (triangles), below

`dome` writes a build target, not a hub mesh: the shallow dome z = -x^2/(2 R1) - y^2/(2 R2)
over LX x LY mm in plan (principal radii R1 along x and R2 along y at the apex), as a
triangle mesh of N x round(N LY / LX) grid cells, each split in two.

`wave_oval` writes the wave canopy of the issue 16 suite, z = 350 sin(x/1000) cos(y/1400),
over an ellipse of semi-axes A along x and B along y instead of a rectangle: the footprint
has no corner, so the automatic layout is the O-grid with four valence-3 vertices (the
10,000-face benchmark with singular vertices). Triangles between N concentric rings of
6, 12, ... 6N points.
"""
import math
import sys


def grid(nx, ny, position):
    verts = [position(i, j) for j in range(ny + 1) for i in range(nx + 1)]
    vid = lambda i, j: j * (nx + 1) + i
    faces = [(vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1))
             for j in range(ny) for i in range(nx)]
    return verts, faces


def sphere_cap(nx, ny, radius, spacing):
    step = spacing / radius
    u0, v0 = nx * step / 2, ny * step / 2

    def pos(i, j):
        lon, lat = i * step - u0, j * step - v0
        return (radius * math.cos(lat) * math.sin(lon), radius * math.sin(lat),
                radius * math.cos(lat) * math.cos(lon) - radius)
    return grid(nx, ny, pos)


def saddle(nx, ny, spacing, r):
    x0, y0 = nx * spacing / 2, ny * spacing / 2

    def pos(i, j):
        x, y = i * spacing - x0, j * spacing - y0
        return (x, y, x * x / (2 * r) - y * y / (2 * r))
    return grid(nx, ny, pos)


def dome(lx, ly, r1, r2, n):
    ny = max(1, round(n * ly / lx))
    verts = []
    for j in range(ny + 1):
        for i in range(n + 1):
            x, y = i * lx / n - lx / 2, j * ly / ny - ly / 2
            verts.append((x, y, -x * x / (2 * r1) - y * y / (2 * r2)))
    vid = lambda i, j: j * (n + 1) + i
    tris = []
    for j in range(ny):
        for i in range(n):
            a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
            tris += [(a, b, c), (a, c, d)]
    return verts, tris


def wave_oval(a, b, n):
    verts = [(0.0, 0.0, 0.0)]
    rings = [[0]]
    for k in range(1, n + 1):
        ring = []
        for i in range(6 * k):
            t = 2 * math.pi * i / (6 * k)
            x, y = a * k / n * math.cos(t), b * k / n * math.sin(t)
            ring.append(len(verts))
            verts.append((x, y, 350 * math.sin(x / 1000) * math.cos(y / 1400)))
        rings.append(ring)
    tris = []
    for k in range(1, n + 1):
        inner, outer = rings[k - 1], rings[k]
        # walk both rings by angle, one triangle per step (counter-clockwise seen from +z)
        m, big = len(inner), len(outer)
        i = j = 0
        while i < m or j < big:
            if i == m or (m > 1 and j < big and (j + 1) / big <= (i + 1) / m) or m == 1:
                tris.append((outer[j], outer[(j + 1) % big], inner[i % m]))
                j += 1
                if m == 1 and j == big:
                    i = m
            else:
                tris.append((inner[i], outer[j % big], inner[(i + 1) % m]))
                i += 1
    return verts, tris


def write(path, about, mesh):
    verts, faces = mesh
    with open(path, "w") as f:
        kind = "quad" if len(faces[0]) == 4 else "triangle"
        f.write(f"# {about}\n# {kind} mesh, units: mm, {len(verts)} vertices, {len(faces)} faces\n")
        for v in verts:
            f.write("v %r %r %r\n" % v)
        for q in faces:
            f.write("f " + " ".join(str(k + 1) for k in q) + "\n")


def main(argv):
    kind = argv[1]
    if kind == "cap":
        nx, ny, radius, spacing, out = int(argv[2]), int(argv[3]), float(argv[4]), float(argv[5]), argv[6]
        write(out, f"sphere cap {nx} x {ny}, R = {radius} mm, spacing {spacing} mm",
              sphere_cap(nx, ny, radius, spacing))
    elif kind == "saddle":
        nx, ny, spacing, r, out = int(argv[2]), int(argv[3]), float(argv[4]), float(argv[5]), argv[6]
        write(out, f"saddle {nx} x {ny}, z = (x^2 - y^2)/(2 x {r}) mm, spacing {spacing} mm",
              saddle(nx, ny, spacing, r))
    elif kind == "dome":
        lx, ly, r1, r2, n, out = (float(argv[2]), float(argv[3]), float(argv[4]),
                                  float(argv[5]), int(argv[6]), argv[7])
        write(out, f"shallow dome {lx:g} x {ly:g} mm, principal radii {r1:g} and {r2:g} mm",
              dome(lx, ly, r1, r2, n))
    elif kind == "wave_oval":
        a, b, n, out = float(argv[2]), float(argv[3]), int(argv[4]), argv[5]
        write(out, f"wave canopy z = 350 sin(x/1000) cos(y/1400) mm over an ellipse {a:g} x {b:g} mm",
              wave_oval(a, b, n))
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv)
