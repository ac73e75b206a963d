#!/usr/bin/env python3
"""Exact (rational) recheck of the area test of check_tin.py, whose float sum
misreports slivers of ~1e-13 m² total area.  usage: exact_area.py MESH.obj
Exits 0 if the triangles are all strictly CCW and their exact area equals the
exact convex hull area of the vertices, else prints why and exits 1."""
import sys
from fractions import Fraction as F
V, T = [], []
for line in open(sys.argv[1]):
    p = line.split()
    if line.startswith("v "):
        V.append((F(float(p[1])), F(float(p[2]))))
    elif line.startswith("f "):
        T.append([int(s.split("/")[0]) - 1 for s in p[1:]])
def o(a, b, c):
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
bad = sum(1 for a, b, c in T if o(V[a], V[b], V[c]) <= 0)
area = sum(o(V[a], V[b], V[c]) for a, b, c in T) / 2
pts = sorted(set(V))
def half(seq):
    h = []
    for q in seq:
        while len(h) >= 2 and o(h[-2], h[-1], q) <= 0:
            h.pop()
        h.append(q)
    return h
lo, up = half(pts), half(list(reversed(pts)))
h = lo[:-1] + up[:-1]
hull = sum(o(h[0], h[i], h[i + 1]) for i in range(1, len(h) - 1)) / 2
if bad or area != hull:
    print("exact: %d non-CCW triangles, area %r vs hull %r" % (bad, float(area), float(hull)))
    sys.exit(1)
print("exact area equals hull area %r" % float(hull))
