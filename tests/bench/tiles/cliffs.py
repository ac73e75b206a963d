#!/usr/bin/env python3
"""A mesa's contours and spot heights, for the steep-terrain benchmark
(cliffs.sh): a plateau 600 m above a plain, its rim a wobbling ring of about
2 km radius, its walls WALL metres wide from foot to rim, contoured every
50 m; the plateau domes 50 m, the plain falls gently outward; 300 spot
heights at random over a 10 km square in UTM-sized coordinates.

  cliffs.py OUT_DIR WALL        writes OUT_DIR/contours.geojson, spots.xyz
"""
import json
import math
import random
import sys

X0, Y0, SIDE = 500000.0, 4500000.0, 10000.0
CX, CY = X0 + SIDE / 2, Y0 + SIDE / 2
FOOT, RIM, STEP = 1000.0, 1600.0, 50.0
SPACING = 2.0  # metres between contour vertices along a ring


def rim_radius(theta):
    return 2000.0 + 150.0 * math.sin(5 * theta) + 60.0 * math.sin(13 * theta + 1.0)


def height(x, y, wall):
    """The mesa's surface: the contours and the spots are both taken from it."""
    r = math.hypot(x - CX, y - CY)
    rim = rim_radius(math.atan2(y - CY, x - CX))
    if r <= rim:
        return RIM + 50.0 * (1 - (r / rim) ** 2)
    if r >= rim + wall:
        return FOOT - 0.02 * (r - rim - wall)
    return RIM - (RIM - FOOT) * (r - rim) / wall


def ring(offset, z):
    """A closed contour `offset` metres outside the rim, at z."""
    n = int(2 * math.pi * 2200 / SPACING)
    points = []
    for i in range(n):
        t = 2 * math.pi * i / n
        r = rim_radius(t) + offset
        points.append([round(CX + r * math.cos(t), 3), round(CY + r * math.sin(t), 3), z])
    return points + [points[0]]


def main():
    out, wall = sys.argv[1], float(sys.argv[2])
    features = []
    levels = int((RIM - FOOT) / STEP)
    for k in range(levels + 1):  # the wall: foot (k = 0) to rim (k = levels)
        z = FOOT + k * STEP
        features.append(ring(wall * (1 - k / levels), z))
    for z in (950.0,):  # the plain falls 0.02 m a metre outward
        offset = wall + (FOOT - z) / 0.02
        features.append(ring(offset, z))
    geojson = {
        "type": "FeatureCollection",
        "features": [
            {"type": "Feature", "properties": {"elev": f[0][2]},
             "geometry": {"type": "LineString", "coordinates": f}}
            for f in features
        ],
    }
    with open(f"{out}/contours.geojson", "w") as f:
        json.dump(geojson, f)
    rng = random.Random(7)
    with open(f"{out}/spots.xyz", "w") as f:
        for _ in range(300):
            x, y = X0 + rng.random() * SIDE, Y0 + rng.random() * SIDE
            f.write(f"{x:.3f} {y:.3f} {height(x, y, wall):.3f}\n")


if __name__ == "__main__":
    main()
