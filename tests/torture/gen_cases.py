#!/usr/bin/env python3
"""Torture inputs for `tinsmith tin` plain mode (standard library only).

usage: gen_cases.py OUTDIR
Writes OUTDIR/<case>/P.xyz (points), optionally B.geojson / B.txt (break lines),
and OUTDIR/cases.tsv with one line per case:
  name  expect  snap  tol  breaklines
expect: 'ok' (must build, validate, and pass check_tin.py) or an exit code the
tin command must return (3 input, 4 geometry) with no output file left behind.
tol: the --tol given to check_tin.py. breaklines: B.geojson, B.txt or '-'.
Coordinates are written with %.17g. Deterministic (fixed seeds)."""
import json, math, os, random, sys

OUT = sys.argv[1] if len(sys.argv) > 1 else "torture_cases"
os.makedirs(OUT, exist_ok=True)
manifest = []


def zf(x, y):
    return 100.0 + 0.001 * ((x * 7.1) % 13.0) + 0.002 * ((y * 3.3) % 11.0)


def fmt(v):
    return "%.17g" % v


def write_case(name, pts, lines=None, expect="ok", snap=0.0, tol=0.002, text_lines=False,
               raw_points=None, raw_lines=None):
    d = os.path.join(OUT, name)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "P.xyz"), "w") as f:
        if raw_points is not None:
            f.write(raw_points)
        else:
            for p in pts:
                z = p[2] if len(p) > 2 else zf(p[0], p[1])
                f.write("%s %s %s\n" % (fmt(p[0]), fmt(p[1]), fmt(z)))
    bl = "-"
    if raw_lines is not None:
        bl = "B.txt"
        with open(os.path.join(d, bl), "w") as f:
            f.write(raw_lines)
    elif lines:
        full = [[(v[0], v[1], v[2] if len(v) > 2 else zf(v[0], v[1])) for v in line] for line in lines]
        feats = [{"type": "Feature", "properties": {"id": i},
                  "geometry": {"type": "LineString", "coordinates": [list(v) for v in line]}}
                 for i, line in enumerate(full)]
        with open(os.path.join(d, "B.geojson"), "w") as f:
            json.dump({"type": "FeatureCollection", "features": feats}, f)
        bl = "B.geojson"
        if text_lines:
            bl = "B.txt"
            with open(os.path.join(d, bl), "w") as f:
                f.write("\n\n".join("\n".join(" ".join(fmt(c) for c in v) for v in line) for line in full) + "\n")
    manifest.append((name, str(expect), repr(snap), repr(tol), bl))


def grid(n, h=1.0, ox=0.0, oy=0.0, ang=0.0):
    c, s = math.cos(math.radians(ang)), math.sin(math.radians(ang))
    out = []
    for i in range(n):
        for j in range(n):
            x, y = i * h, j * h
            out.append((ox + c * x - s * y, oy + s * x + c * y))
    return out


def rot(p, ang, ox=0.0, oy=0.0):
    c, s = math.cos(ang), math.sin(ang)
    return (ox + c * p[0] - s * p[1], oy + s * p[0] + c * p[1])


rng = random.Random(12345)

# ---- cocircular grids
write_case("grid_100", grid(100))
write_case("grid_300_rot30", grid(300, ang=30))
write_case("grid_200_rot45", grid(200, ang=45))
write_case("grid_200_utm", grid(200, ox=500000.0, oy=7000000.0))
write_case("grid_150_utm_rot30", grid(150, ox=500000.0, oy=7000000.0, ang=30))
write_case("grid_150_utm_rot45", grid(150, ox=500000.0, oy=7000000.0, ang=45))
write_case("grid_100_utm_mm", grid(100, h=0.001, ox=500000.0, oy=7000000.0), tol=1e-4)
write_case("grid_100_utm_mm_rot45", grid(100, h=0.001, ox=500000.0, oy=7000000.0, ang=45), tol=1e-4)
# grid with diagonal break lines through every cocircular cell row
g = grid(60, ox=500000.0, oy=7000000.0)
write_case("grid_utm_diag_constraints", g,
           [[(500000.0 + i, 7000000.0), (500000.0 + 59, 7000000.0 + 59 - i)] for i in range(0, 59, 3)])
# ---- circles
write_case("circle_1000", [(1000 * math.cos(2 * math.pi * k / 1000), 1000 * math.sin(2 * math.pi * k / 1000)) for k in range(1000)])
write_case("circle_1000_utm", [(500000 + 100 * math.cos(2 * math.pi * k / 1000), 7000000 + 100 * math.sin(2 * math.pi * k / 1000)) for k in range(1000)])
write_case("circle_center", [(0.0, 0.0)] + [(10 * math.cos(2 * math.pi * k / 720), 10 * math.sin(2 * math.pi * k / 720)) for k in range(720)])
write_case("two_circles", [(r * math.cos(2 * math.pi * k / 500), r * math.sin(2 * math.pi * k / 500)) for r in (10.0, 20.0) for k in range(500)])
write_case("two_circles_utm_aligned", [(500000 + r * math.cos(2 * math.pi * k / 256), 7000000 + r * math.sin(2 * math.pi * k / 256)) for r in (10.0, 20.0) for k in range(256)])
# ---- collinear
line = [(i * 1.0, 0.0) for i in range(1000)]
write_case("collinear_1000_plus1", line + [(500.0, 1.0)])
write_case("collinear_1000_plus1_utm", [(500000 + i * 0.37, 7000000 + i * 0.37) for i in range(1000)] + [(500100.0, 7000000.0)])
write_case("collinear_1000_plus1_far", line + [(500.0, 1e-7)])
pts = []
for i in range(1000):
    x = 500000.0 + i * 0.5
    y = 7000000.0 + i * 0.5
    k = i % 3
    if k == 1:
        y = math.nextafter(y, math.inf)
    elif k == 2:
        y = math.nextafter(y, -math.inf)
    pts.append((x, y))
write_case("line_1ulp_perturbed_utm", pts)
pts = [(i * 0.1, i * 0.1) for i in range(1000)]
pts = [(x, math.nextafter(y, math.inf) if i % 2 else y) for i, (x, y) in enumerate(pts)]
write_case("line_1ulp_perturbed", pts)
# ---- duplicates
base = grid(50, ox=500000.0, oy=7000000.0)
dup = []
for p in base:
    for k in range(5):
        dup.append((p[0], p[1], 100.0 + k))
write_case("dups_5x_samexy", dup)
write_case("dups_5x_samexy_snap", dup, snap=0.01)
nd = []
for p in base:
    nd.append(p)
    nd.append((p[0] + 0.0004, p[1]))      # within snap 0.001
    nd.append((p[0], p[1] + 0.0011))      # just outside snap 0.001
write_case("near_dups_snap", nd, snap=0.001)
nd2 = []
for p in base:
    nd2.append(p)
    nd2.append((math.nextafter(p[0], math.inf), p[1]))
    nd2.append((p[0], math.nextafter(p[1], -math.inf)))
write_case("near_dups_1ulp_nosnap", nd2)
write_case("near_dups_1ulp_snap", nd2, snap=1e-6)
chain = [(500000.0 + i * 0.0009, 7000000.0) for i in range(200)] + [(500000.0, 7000001.0), (500000.2, 6999999.0)]
write_case("snap_chain", chain, snap=0.001)
# ---- constraints
rp = [(rng.uniform(-100, 100), rng.uniform(-100, 100)) for _ in range(3000)]
star = [[(100 * math.cos(math.pi * k / 50), 100 * math.sin(math.pi * k / 50)),
         (-100 * math.cos(math.pi * k / 50), -100 * math.sin(math.pi * k / 50))] for k in range(50)]
write_case("star_50_through_point", rp + [(0.0, 0.0)], star)
write_case("star_50_through_nonpoint", rp, star)
starU = [[(500000.0 + a[0], 7000000.0 + a[1]), (500000.0 + b[0], 7000000.0 + b[1])] for a, b in star]
write_case("star_50_utm", [(500000.0 + x, 7000000.0 + y) for x, y in rp], starU)
write_case("overlap_collinear", rp,
           [[(-90.0, 0.0), (50.0, 0.0)], [(-20.0, 0.0), (90.0, 0.0)], [(-10.0, 0.0), (10.0, 0.0)],
            [(-90.0, 0.0), (90.0, 0.0)], [(-50.0, -50.0), (50.0, 50.0)], [(-20.0, -20.0), (20.0, 20.0)],
            [(0.0, 0.0), (60.0, 60.0)]])
write_case("overlap_collinear_utm", [(500000.0 + x, 7000000.0 + y) for x, y in rp],
           [[(500000.0 - 90.3, 7000000.0 - 30.1), (500000.0 + 60.6, 7000000.0 + 20.2)],
            [(500000.0 - 30.3, 7000000.0 - 10.1), (500000.0 + 90.3, 7000000.0 + 30.1)],
            [(500000.0 - 3.03, 7000000.0 - 1.01), (500000.0 + 3.03, 7000000.0 + 1.01)]])
tiny = []
for k in range(20):
    a = 1e-9 * (k + 1)
    tiny.append([rot((-90.0, 0.0), a), rot((90.0, 0.0), a)])
write_case("tiny_angle_1e-9", rp, tiny)
tinyU = [[rot((-90.0, 0.0), 1e-9 * (k + 1), 500000.0, 7000000.0), rot((90.0, 0.0), 1e-9 * (k + 1), 500000.0, 7000000.0)] for k in range(20)]
write_case("tiny_angle_1e-9_utm", [(500000.0 + x, 7000000.0 + y) for x, y in rp], tinyU)
write_case("tiny_angle_pair_utm", [(500000.0 + x, 7000000.0 + y) for x, y in rp],
           [[rot((-90.0, 0.0), 0.0, 500000.0, 7000000.0), rot((90.0, 0.0), 0.0, 500000.0, 7000000.0)],
            [rot((-90.0, 0.0), 1e-9, 500000.0, 7000000.3), rot((90.0, 0.0), 1e-9, 500000.0, 7000000.3)]])
write_case("t_junctions", rp,
           [[(-80.0, 0.0), (80.0, 0.0)]] + [[(x, 0.0), (x, 70.0)] for x in range(-70, 71, 10)]
           + [[(x + 5.0, -60.0), (x + 5.0, 0.0)] for x in range(-70, 61, 10)])
gl = grid(101, ox=-50.0, oy=-50.0)
write_case("through_100_vertices", gl, [[(-50.0, 0.0), (50.0, 0.0)], [(-50.0, -50.0), (50.0, 50.0)]])
glu = grid(101, h=0.1, ox=500000.0, oy=7000000.0)
write_case("through_100_vertices_utm", glu,
           [[(500000.0, 7000000.0 + 5.0), (500000.0 + 10.0, 7000000.0 + 5.0)],
            [(500000.0, 7000000.0), (500000.0 + 10.0, 7000000.0 + 10.0)]])
fig8 = [(60 * math.sin(2 * math.pi * k / 200), 30 * math.sin(4 * math.pi * k / 200)) for k in range(201)]
pent = [(80 * math.cos(math.pi / 2 + 4 * math.pi * k / 5), 80 * math.sin(math.pi / 2 + 4 * math.pi * k / 5)) for k in range(6)]
star7 = [(70 * math.cos(6 * math.pi * k / 7), 70 * math.sin(6 * math.pi * k / 7)) for k in range(8)]
write_case("self_crossing", rp, [fig8, pent, star7])
write_case("self_crossing_txt", rp, [fig8, pent, star7], text_lines=True)
U = 500000.0; V = 7000000.0
segs = [[(U + 1000 * rng.random(), V + 1000 * rng.random()), (U + 1000 * rng.random(), V + 1000 * rng.random())] for _ in range(1000)]
write_case("random_1000_segments_utm", [(U + 1000 * rng.random(), V + 1000 * rng.random()) for _ in range(5000)], segs)
segs2 = [[(U + rng.random(), V + rng.random()), (U + rng.random(), V + rng.random())] for _ in range(300)]
write_case("random_300_segments_utm_1m", [(U + rng.random(), V + rng.random()) for _ in range(500)] + [(U, V), (U + 1, V), (U, V + 1), (U + 1, V + 1)], segs2, tol=1e-5)
write_case("endpoints_not_points", rp, [[(-73.3, 12.1), (55.5, -44.4), (10.0, 90.0)], [(0.123, 0.456), (0.789, 0.1011)]])
sq = [(0.0, 0.0), (100.0, 0.0), (100.0, 100.0), (0.0, 100.0)] + [(rng.uniform(1, 99), rng.uniform(1, 99)) for _ in range(2000)] + [(x, 0.0) for x in range(1, 100, 7)]
write_case("constraint_on_hull", sq, [[(0.0, 0.0), (100.0, 0.0), (100.0, 100.0), (0.0, 100.0), (0.0, 0.0)]])
write_case("constraint_outside_hull", sq, [[(-10.0, -10.0), (110.0, -10.0)], [(50.0, 50.0), (150.0, 50.0)]])
rings = [[(0.0, 0.0), (40.0, 0.0), (40.0, 40.0), (0.0, 40.0), (0.0, 0.0)],
         [(40.0, 0.0), (80.0, 0.0), (80.0, 40.0), (40.0, 40.0), (40.0, 0.0)],
         [(0.0, 0.0), (40.0, 40.0), (0.0, 80.0), (-40.0, 40.0), (0.0, 0.0)],
         [(40.0, 40.0), (60.0, 20.0), (80.0, 40.0), (60.0, 60.0), (40.0, 40.0)]]
write_case("rings_sharing_vertices", rp, rings)
write_case("rings_sharing_vertices_txt", rp, rings, text_lines=True)
write_case("constraint_dup_vertices", rp, [[(-50.0, -50.0), (-50.0, -50.0), (50.0, 50.0), (50.0, 50.0), (50.0, -50.0)]])
write_case("constraint_zero_length", rp, [[(1.0, 1.0), (1.0, 1.0)]])
write_case("constraint_z_conflict", rp, [[(-50.0, 0.0, 10.0), (50.0, 0.0, 10.0)], [(0.0, -50.0, 20.0), (0.0, 50.0, 20.0)]])
# ---- magnitudes
write_case("huge_1e9", [(1e9 + rng.uniform(0, 1e6), 1e9 + rng.uniform(0, 1e6)) for _ in range(5000)],
           [[(1e9 + 1e5, 1e9 + 1e5), (1e9 + 9e5, 1e9 + 9e5)], [(1e9 + 1e5, 1e9 + 9e5), (1e9 + 9e5, 1e9 + 1e5)]])
write_case("huge_1e9_grid", grid(100, h=1000.0, ox=1e9, oy=1e9))
write_case("tiny_spacing_7e6", [(U + 1e-3 * rng.random() * 100, 7e6 + 1e-3 * rng.random() * 100) for _ in range(3000)], tol=1e-6)
write_case("tiny_grid_1mm_7e6", grid(120, h=1e-3, ox=7e6, oy=7e6), tol=1e-5)
write_case("tiny_coords_1e-6", [(rng.random() * 1e-6, rng.random() * 1e-6) for _ in range(2000)], tol=1e-10)
# ---- nastier mixes
write_case("constraint_1ulp_beside_vertices_utm", glu,
           [[(500000.0, 7000000.0 + 5.0), (500000.0 + 10.0, math.nextafter(7000000.0 + 5.0, math.inf))],
            [(500000.0, math.nextafter(7000000.0 + 2.0, -math.inf)), (500000.0 + 10.0, 7000000.0 + 2.0)]])
fan = [[rot((-50.0, 0.0), 1e-9 * k, U + 0.3, V + 0.7), rot((50.0, 0.0), 1e-9 * k, U + 0.3, V + 0.7)] for k in range(50)]
write_case("fan_50_near_parallel_utm", [(U + rng.uniform(-60, 60), V + rng.uniform(-60, 60)) for _ in range(2000)], fan)
nodes = [(U + 10.0 * i, V + 10.0 * j) for i in range(11) for j in range(11)]
gsegs = []
for _ in range(500):
    a, b = rng.sample(nodes, 2)
    gsegs.append([a, b])
write_case("lattice_500_segments_utm", [(U + rng.uniform(0, 100), V + rng.uniform(0, 100)) for _ in range(2000)] + nodes, gsegs)
for name, (ox, oy) in (("lattice_3_segments_utm", (U, V)), ("lattice_3_segments", (0.0, 0.0))):
    # reduced from lattice_500_segments_utm: the third segment passes exactly through node (50, 70)
    write_case(name, [(ox + 10.0 * i, oy + 10.0 * j) for i in range(11) for j in range(11)],
               [[(ox + 40.0, oy + 60.0), (ox + 70.0, oy + 60.0)], [(ox + 60.0, oy + 40.0), (ox + 40.0, oy + 100.0)],
                [(ox + 60.0, oy + 80.0), (ox + 40.0, oy + 60.0)]])
write_case("concurrent_3_through_node_utm", [(U + 10.0 * i, V + 10.0 * j) for i in range(11) for j in range(11)],
           [[(U + 30, V + 0), (U + 70, V + 100)], [(U + 0, V + 50), (U + 100, V + 50)], [(U + 10, V + 30), (U + 90, V + 70)]])
# three break lines through input node (50, 70): check_tin passes but the TIN gets two extra
# vertices 1e-10 m and 2.3e-10 m from the node (count near-coincident vertices in out.obj)
write_case("concurrent_5_through_node_utm", [(U + 10.0 * i, V + 10.0 * j) for i in range(11) for j in range(11)],
           [[(U + 80, V + 10), (U + 0, V + 80)], [(U + 70, V + 0), (U + 90, V + 20)], [(U + 30, V + 0), (U + 70, V + 100)],
            [(U + 0, V + 50), (U + 100, V + 50)], [(U + 10, V + 30), (U + 90, V + 70)]])
# ---- medium random + mixed (perf)
write_case("random_100k_utm", [(U + 5000 * rng.random(), V + 5000 * rng.random()) for _ in range(100000)],
           [[(U + 5000 * rng.random(), V + 5000 * rng.random()) for _ in range(20)] for _ in range(50)])
write_case("grid_400_utm_160k", grid(400, ox=U, oy=V))
# ---- bad input
gp = grid(10)
def raw(pts):
    return "".join("%s %s %s\n" % (fmt(p[0]), fmt(p[1]), fmt(zf(p[0], p[1]))) for p in pts)
write_case("bad_nan_xy", None, expect=3, raw_points=raw(gp) + "nan 1 2\n")
write_case("bad_nan_z", None, expect=3, raw_points=raw(gp) + "1.5 1.5 nan\n")
write_case("bad_inf", None, expect=3, raw_points=raw(gp) + "inf 1 2\n")
write_case("bad_neg_inf_y", None, expect=3, raw_points=raw(gp) + "1 -inf 2\n")
write_case("bad_1e400", None, expect=3, raw_points=raw(gp) + "1e400 1 2\n")
write_case("bad_empty", None, expect=3, raw_points="")
write_case("bad_blank_lines", None, expect=3, raw_points="\n\n   \n")
write_case("bad_2_points", None, expect=4, raw_points="0 0 1\n1 1 2\n")
write_case("bad_3_collinear", None, expect=4, raw_points="0 0 1\n1 1 2\n2 2 3\n")
write_case("bad_all_collinear", None, expect=4, raw_points=raw([(i * 1.0, 2 * i * 1.0) for i in range(1000)]))
write_case("bad_all_same_xy", None, expect=4, raw_points="".join("5 5 %d\n" % i for i in range(100)))
write_case("bad_garbage", None, expect=3, raw_points=raw(gp) + "hello world foo\n")
write_case("bad_garbage_trailing", None, expect=3, raw_points=raw(gp) + "1 2 3abc\n")
write_case("bad_two_columns", None, expect=3, raw_points=raw(gp) + "1 2\n")
write_case("bad_binary", None, expect=3, raw_points="\x00\x01\x02\xff\xfe garbage\n")
write_case("bad_bl_nan", gp, expect=3, raw_lines="1 1 1\nnan 2 2\n")
write_case("bad_bl_inf", gp, expect=3, raw_lines="1 1 1\n2 inf 2\n")
write_case("bad_bl_garbage", gp, expect=3, raw_lines="1 1 1\nfoo bar baz\n")
write_case("bad_bl_single_vertex", gp, expect=3, raw_lines="1 1 1\n\n2 2 2\n3 3 3\n")
write_case("bad_bl_empty", gp, expect=3, raw_lines="")
write_case("bad_bl_no_z", gp, expect=3, raw_lines="1 1\n2 2\n")

with open(os.path.join(OUT, "cases.tsv"), "w") as f:
    for m in manifest:
        f.write("\t".join(m) + "\n")
print("%d cases in %s" % (len(manifest), OUT))
