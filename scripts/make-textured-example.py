#!/usr/bin/env python3
"""Generates examples/textured/: a glazed and gilded vase as a glTF 2.0 file with its three textures, and the
red-and-white checker of the textured Cornell box's floor (examples/cornell-textured.json).

    python3 scripts/make-textured-example.py [OUTPUT_DIR]      (default: examples/textured next to this script)

Python 3 standard library only: the PNGs are written with zlib and struct. The output is the same bytes on every
run (no randomness, no time stamps; floats are rounded before they are written).

The vase is a surface of revolution (a lathe) about +y, in metres, standing on y = 0: an outer wall, a rounded
rim, an inner wall 4 mm inside it and two flat bottoms (outside and inside), 0.24 m tall and 0.16 m across at the
belly. Texture coordinates: u runs once around (the seam at +z has its own column of vertices), v down the
outer wall from the rim to the foot ([0, 0.8] by arc length), then the outer bottom, the rim's top and the inside
(regions below). Seen from outside, u runs to the right and v down, so the textures are not mirrored. The
tangents are dP/du with the handedness w that makes w * cross(n, t) point up the image (towards -dP/dv), glTF's
convention for the normal map's green channel.

The material is glTF's metallic-roughness model:
  base colour (sRGB)      cobalt glaze on the neck and the lower body, an ivory belly painted with a cobalt vine,
                          gilded rim and bands, an unglazed terracotta foot;
  metallic-roughness      G: roughness 0.12 on the glazes, 0.28 on the gold, 0.85 on the terracotta;
                          B: metallic 1 on the gold, 0 elsewhere (R, occlusion, is 1);
  normal (tangent space)  from a height field: grooves around the neck, raised dots, ridges along the gold
                          bands, the painted vine raised like slip, flutes on the lower body.
"""

import json
import math
import os
import struct
import sys
import zlib

# ---- PNG -------------------------------------------------------------------------------------------------------


def write_png(path, width, height, rows):
    """rows: `height` bytes objects of width * 3 bytes (RGB, 8 bit). Each row takes the PNG filter (none, sub,
    up, average) with the smallest sum of absolute values, the usual heuristic; zlib level 9."""
    raw = bytearray()
    previous = bytes(width * 3)
    for row in rows:
        candidates = [bytes([0]) + row]
        sub = bytearray(row)
        up = bytearray(row)
        avg = bytearray(row)
        for i in range(len(row)):
            left = row[i - 3] if i >= 3 else 0
            sub[i] = (row[i] - left) & 0xFF
            up[i] = (row[i] - previous[i]) & 0xFF
            avg[i] = (row[i] - ((left + previous[i]) >> 1)) & 0xFF
        candidates += [bytes([1]) + bytes(sub), bytes([2]) + bytes(up), bytes([3]) + bytes(avg)]
        cost = lambda c: sum(b if b < 128 else 256 - b for b in c[1:])
        raw += min(candidates, key=cost)
        previous = row

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
    png += chunk(b"sRGB", bytes([0]))  # perceptual; the base colour is sRGB, the other maps are read as linear
    png += chunk(b"IDAT", zlib.compress(bytes(raw), 9))
    png += chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def srgb_encode(linear):
    c = min(max(linear, 0.0), 1.0)
    c = 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055
    return int(round(c * 255))


def byte(value):
    return int(round(min(max(value, 0.0), 1.0) * 255))


# ---- the vase's profile ----------------------------------------------------------------------------------------

HEIGHT = 0.24
WALL = 0.004  # wall thickness
FLOOR = 0.012  # the inner bottom's height
FOOT = 0.016  # the unglazed foot ring
# Outer radius at heights y (metres): foot, waist, belly, shoulder, neck, flared lip.
CONTROL = [(0.0, 0.050), (0.016, 0.048), (0.030, 0.050), (0.070, 0.074), (0.100, 0.080), (0.130, 0.074),
           (0.160, 0.052), (0.185, 0.036), (0.210, 0.036), (0.232, 0.046), (HEIGHT, 0.050)]


def outer_radius(y):
    """Monotone cubic (Fritsch-Carlson) through CONTROL: smooth, no overshoot."""
    ys = [p[0] for p in CONTROL]
    rs = [p[1] for p in CONTROL]
    n = len(CONTROL)
    d = [(rs[i + 1] - rs[i]) / (ys[i + 1] - ys[i]) for i in range(n - 1)]
    m = [d[0]] + [0.0 if d[i - 1] * d[i] <= 0 else (d[i - 1] + d[i]) / 2 for i in range(1, n - 1)] + [d[-1]]
    for i in range(n - 1):
        if d[i] == 0:
            m[i] = m[i + 1] = 0.0
        else:
            a, b = m[i] / d[i], m[i + 1] / d[i]
            if a * a + b * b > 9:
                t = 3 / math.hypot(a, b)
                m[i], m[i + 1] = t * a * d[i], t * b * d[i]
    i = max(0, min(n - 2, next((k for k in range(n - 1) if y <= ys[k + 1]), n - 2)))
    h = ys[i + 1] - ys[i]
    t = (y - ys[i]) / h
    h00, h10 = 2 * t ** 3 - 3 * t ** 2 + 1, t ** 3 - 2 * t ** 2 + t
    h01, h11 = -2 * t ** 3 + 3 * t ** 2, t ** 3 - t ** 2
    return h00 * rs[i] + h10 * h * m[i] + h01 * rs[i + 1] + h11 * h * m[i + 1]


def resample(points, count):
    """`count` points spaced evenly by arc length along the polyline `points` (r, y)."""
    lengths = [0.0]
    for a, b in zip(points, points[1:]):
        lengths.append(lengths[-1] + math.dist(a, b))
    result = []
    k = 0
    for j in range(count):
        s = lengths[-1] * j / (count - 1)
        while k < len(points) - 2 and lengths[k + 1] < s:
            k += 1
        t = (s - lengths[k]) / (lengths[k + 1] - lengths[k])
        result.append((points[k][0] + t * (points[k + 1][0] - points[k][0]),
                       points[k][1] + t * (points[k + 1][1] - points[k][1])))
    return result


def profile_normals(points, outward):
    """Unit (nr, ny) normals of a profile polyline from its neighbours' differences; `outward` picks the side."""
    normals = []
    for j in range(len(points)):
        a = points[max(j - 1, 0)]
        b = points[min(j + 1, len(points) - 1)]
        dr, dy = b[0] - a[0], b[1] - a[1]
        length = math.hypot(dr, dy)
        nr, ny = dy / length, -dr / length
        normals.append((nr, ny) if outward(points[j], (nr, ny)) else (-nr, -ny))
    return normals


# Texture regions along v (the outer wall takes most of the image).
V_OUTER = (0.0, 0.80)
V_BOTTOM = (0.80, 0.84)
V_RIM = (0.84, 0.87)
V_INNER = (0.87, 0.98)
V_INNER_BOTTOM = (0.98, 1.0)


def make_runs():
    """The profile as runs of (r, y) points with their normals and v: the seams between runs are hard edges."""
    dense = [(outer_radius(HEIGHT * (1 - i / 2000)), HEIGHT * (1 - i / 2000)) for i in range(2001)]
    outer = resample(dense, 40)  # from the lip's top down to the foot's bottom edge
    runs = []
    away_from_axis = lambda p, n: n[0] > 0 or (abs(n[0]) < 1e-9 and n[1] > 0)
    runs.append(("outer", outer, profile_normals(outer, away_from_axis), V_OUTER))
    bottom = [(outer[-1][0] * (1 - i / 4), 0.0) for i in range(5)]
    runs.append(("bottom", bottom, [(0.0, -1.0)] * len(bottom), V_BOTTOM))
    # The rim: a half circle over the wall's top, from the inner wall's top to the outer one's.
    r_top = outer[0][0]
    centre = (r_top - WALL / 2, HEIGHT)
    rim = [(centre[0] - WALL / 2 * math.cos(math.pi * i / 6), centre[1] + WALL / 2 * math.sin(math.pi * i / 6))
           for i in range(7)]
    rim_normals = [(-math.cos(math.pi * i / 6), math.sin(math.pi * i / 6)) for i in range(7)]
    runs.append(("rim", rim, rim_normals, V_RIM))
    # The inner wall, WALL inside the outer one (horizontally), from the top down to the inner bottom.
    inner_dense = [(outer_radius(y) - WALL, y) for y in
                   (HEIGHT - (HEIGHT - FLOOR) * i / 1000 for i in range(1001))]
    inner = resample(inner_dense, 14)
    runs.append(("inner", inner, profile_normals(inner, lambda p, n: n[0] < 0), V_INNER))
    inner_bottom = [(inner[-1][0] * (1 - i / 4), FLOOR) for i in range(5)]
    runs.append(("inner_bottom", inner_bottom, [(0.0, 1.0)] * len(inner_bottom), V_INNER_BOTTOM))
    return runs


def arc_v(points, v_range):
    lengths = [0.0]
    for a, b in zip(points, points[1:]):
        lengths.append(lengths[-1] + math.dist(a, b))
    return [v_range[0] + (v_range[1] - v_range[0]) * s / lengths[-1] for s in lengths]


SEGMENTS = 64  # around the axis


def build_mesh():
    positions, normals, uvs, tangents, triangles = [], [], [], [], []
    runs = make_runs()
    for name, points, run_normals, v_range in runs:
        vs = arc_v(points, v_range)
        first = len(positions)
        for (r, y), (nr, ny), v in zip(points, run_normals, vs):
            for k in range(SEGMENTS + 1):
                u = k / SEGMENTS
                theta = 2 * math.pi * u
                s, c = math.sin(theta), math.cos(theta)
                positions.append((r * s, y, r * c))
                normals.append((nr * s, ny, nr * c))
                uvs.append((u, v))
                tangents.append([c, 0.0, -s, 1.0])  # dP/du, normalized; w set below
        rows = len(points)
        for j in range(rows - 1):
            for k in range(SEGMENTS):
                a = first + j * (SEGMENTS + 1) + k
                b, c_, d = a + 1, a + SEGMENTS + 1, a + SEGMENTS + 2
                for tri in ((a, c_, b), (b, c_, d)):
                    p = [positions[i] for i in tri]
                    e1 = [p[1][i] - p[0][i] for i in range(3)]
                    e2 = [p[2][i] - p[0][i] for i in range(3)]
                    face = cross(e1, e2)
                    if dot(face, face) < 1e-18:
                        continue  # the rows meet at the axis: a fan, not a strip
                    n = [sum(normals[i][x] for i in tri) for x in range(3)]
                    triangles.append(tri if dot(face, n) > 0 else (tri[0], tri[2], tri[1]))
        # Handedness: w * cross(n, t) must point up the image, towards -dP/dv (down the run's v).
        for j in range(rows):
            nxt, prv = min(j + 1, rows - 1), max(j - 1, 0)
            for k in range(SEGMENTS + 1):
                i = first + j * (SEGMENTS + 1) + k
                up_image = [positions[first + prv * (SEGMENTS + 1) + k][x] -
                            positions[first + nxt * (SEGMENTS + 1) + k][x] for x in range(3)]
                t = tangents[i]
                if dot(up_image, up_image) < 1e-18:  # on the axis: any tangent frame
                    continue
                t[3] = 1.0 if dot(cross(normals[i], t[:3]), up_image) >= 0 else -1.0
    return positions, normals, uvs, tangents, triangles, runs


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


# ---- the textures ----------------------------------------------------------------------------------------------

SIZE = 512
# Linear colours.
COBALT = (0.020, 0.060, 0.330)
IVORY = (0.800, 0.740, 0.580)
GOLD = (1.000, 0.710, 0.290)  # gold's F0 (metallic 1)
TERRACOTTA = (0.420, 0.160, 0.080)
TURQUOISE = (0.030, 0.300, 0.320)
INSIDE = (0.015, 0.045, 0.250)


class Layout:
    """The outer wall's v at a height y, from the profile's arc length, so that bands can be set in metres."""

    def __init__(self, runs):
        points = runs[0][1]
        self.ys = [p[1] for p in points]
        self.vs = arc_v(points, V_OUTER)
        self.length = sum(math.dist(a, b) for a, b in zip(points, points[1:]))

    def v(self, y):
        for j in range(len(self.ys) - 1):
            if self.ys[j + 1] <= y <= self.ys[j]:
                t = (self.ys[j] - y) / (self.ys[j] - self.ys[j + 1])
                return self.vs[j] + t * (self.vs[j + 1] - self.vs[j])
        return self.vs[0] if y > self.ys[0] else self.vs[-1]

    def metres_per_v(self):
        return self.length / (V_OUTER[1] - V_OUTER[0])


def smooth(edge0, edge1, x):
    t = min(max((x - edge0) / (edge1 - edge0), 0.0), 1.0)
    return t * t * (3 - 2 * t)


LEAF_LENGTH = 0.075  # in texture units along the leaf
LEAF_WIDTH = 0.016  # half the widest part


class Painter:
    """The vase's surface at texture coordinates (u, v): colour, roughness, metallic and relief height."""

    def __init__(self, layout):
        L = layout
        self.gold_rim = L.v(HEIGHT - 0.007)  # v above which the lip is gilded
        self.neck_end = L.v(0.166)
        self.band_end = L.v(0.152)
        self.belly_end = L.v(0.050)
        self.band2_end = L.v(0.042)
        self.foot_start = L.v(FOOT)
        self.belly_mid = (self.band_end + self.belly_end) / 2
        self.belly_half = (self.belly_end - self.band_end) / 2
        self.neck_rows = [self.gold_rim + (self.neck_end - self.gold_rim) * f for f in (0.38, 0.72)]
        # The neck is narrower than the belly: a round dot there is wider in u than in v.
        self.neck_aspect = L.metres_per_v() / (2 * math.pi * outer_radius(0.198))

    def region(self, v):
        if v < V_OUTER[1]:
            if v < self.gold_rim: return "gold"
            if v < self.neck_end: return "neck"
            if v < self.band_end: return "gold"
            if v < self.belly_end: return "belly"
            if v < self.band2_end: return "gold"
            if v < self.foot_start: return "lower"
            return "foot"
        if v < V_BOTTOM[1]: return "foot"
        if v < V_RIM[1]: return "gold"
        return "inside"

    def vine(self, u, v):
        """Distance (in v units) to the painted vine, and to its nearest leaf's centre line: 0 on the paint."""
        centre = self.belly_mid + 0.35 * self.belly_half * math.sin(2 * math.pi * 5 * u)
        slope = 0.35 * self.belly_half * 2 * math.pi * 5 * math.cos(2 * math.pi * 5 * u)
        stem = abs(v - centre) / math.sqrt(1 + slope * slope)
        # A pair of pointed leaves at each crest of the stem, spread 35 degrees either side of the way out
        # (in texture units: on the belly a unit of u is 0.50 m, one of v 0.33 m, so the leaves are drawn wide).
        leaf = 1e9
        for side, phase in ((1, 0.25), (-1, 0.75)):
            uc = (round(u * 5 - phase) + phase) / 5
            vc = self.belly_mid + side * 0.35 * self.belly_half
            for tilt in (-1, 1):
                angle = math.radians(35)
                axis = (tilt * math.sin(angle), side * math.cos(angle))
                du, dv = u - uc, v - vc
                along = du * axis[0] + dv * axis[1]
                across = -du * axis[1] + dv * axis[0]
                if 0 < along < LEAF_LENGTH:
                    width = LEAF_WIDTH * math.sin(math.pi * along / LEAF_LENGTH) ** 0.8
                    leaf = min(leaf, abs(across) / max(width, 1e-9))
        # A row of dots above and below the vine, 10 around: inside each pair of leaves and over each trough.
        uc = (round(u * 10 - 0.5) + 0.5) / 10
        dots = min(math.hypot((u - uc) / 0.010, (v - (self.belly_mid + side * 0.80 * self.belly_half)) /
                              (0.07 * self.belly_half)) for side in (-1, 1))
        return stem, leaf, dots

    def sample(self, u, v):
        """(linear rgb, roughness, metallic)"""
        region = self.region(v)
        if region == "gold":
            return GOLD, 0.28, 1.0
        if region == "foot":
            # unglazed: a little grain along u
            g = 0.92 + 0.08 * math.sin(2 * math.pi * 37 * u) * math.sin(2 * math.pi * 211 * v)
            return tuple(c * g for c in TERRACOTTA), 0.85, 0.0
        if region == "inside":
            return INSIDE, 0.12, 0.0
        if region == "neck":
            # cobalt with two rows of ivory dots, 16 and 16 offset by half a step
            best = 1e9
            for row, offset in zip(self.neck_rows, (0.0, 0.5)):
                du = ((u * 16 - offset) % 1.0 - 0.5) / 16
                best = min(best, math.hypot(du / (0.012 * self.neck_aspect), (v - row) / 0.012))
            return (IVORY if best < 1 else COBALT), 0.12, 0.0
        if region == "lower":
            return TURQUOISE, 0.12, 0.0
        stem, leaf, dots = self.vine(u, v)
        paint = stem < 0.006 or leaf < 1 or dots < 1
        return (COBALT if paint else IVORY), 0.12, 0.0

    def height(self, u, v):
        """Relief in metres (positive: raised)."""
        region = self.region(v)
        h = 0.0
        if region == "neck":
            # grooves around the neck: 0.6 mm deep, a ridge every 1/9 of the neck
            t = (v - self.gold_rim) / (self.neck_end - self.gold_rim)
            h -= 0.0006 * (0.5 + 0.5 * math.cos(2 * math.pi * 9 * t))
            for row, offset in zip(self.neck_rows, (0.0, 0.5)):
                du = ((u * 16 - offset) % 1.0 - 0.5) / 16
                d = math.hypot(du / (0.014 * self.neck_aspect), (v - row) / 0.014)
                h = max(h, 0.0006 * (1 - d * d)) if d < 1 else h
        elif region == "gold" and v < V_OUTER[1] and v > self.gold_rim:
            # the bands: a raised ridge at each edge
            for a, b in ((self.neck_end, self.band_end), (self.belly_end, self.band2_end)):
                if a <= v <= b:
                    t = (v - a) / (b - a)
                    h += 0.0004 * (math.exp(-((t - 0.15) / 0.1) ** 2) + math.exp(-((t - 0.85) / 0.1) ** 2))
        elif region == "belly":
            stem, leaf, dots = self.vine(u, v)
            h += 0.0005 * smooth(0.009, 0.004, stem)
            h += 0.0005 * smooth(1.2, 0.7, leaf)
            h += 0.0004 * smooth(1.3, 0.5, dots)
        elif region == "lower":
            # 32 flutes around the lower body, fading out towards its ends
            t = (v - self.band2_end) / (self.foot_start - self.band2_end)
            h += 0.0012 * (0.5 + 0.5 * math.cos(2 * math.pi * 32 * u)) * math.sin(math.pi * t)
        return h


def make_textures(directory, layout):
    painter = Painter(layout)
    n = SIZE
    base_rows, mr_rows = [], []
    ss = 3  # supersamples per texel side
    for y in range(n):
        base_row, mr_row = bytearray(), bytearray()
        for x in range(n):
            rgb, rough, metal = [0.0, 0.0, 0.0], 0.0, 0.0
            for sy in range(ss):
                for sx in range(ss):
                    c, r, m = painter.sample((x + (sx + 0.5) / ss) / n, (y + (sy + 0.5) / ss) / n)
                    rgb = [rgb[i] + c[i] for i in range(3)]
                    rough += r
                    metal += m
            k = ss * ss
            base_row += bytes(srgb_encode(c / k) for c in rgb)
            mr_row += bytes((255, byte(rough / k), byte(metal / k)))
        base_rows.append(bytes(base_row))
        mr_rows.append(bytes(mr_row))
    write_png(os.path.join(directory, "vase_basecolor.png"), n, n, base_rows)
    write_png(os.path.join(directory, "vase_metallic_roughness.png"), n, n, mr_rows)

    # Normal map: central differences of the height field, in metres along the surface (u around the belly's
    # circumference at that height, v along the profile's arc length).
    heights = [[painter.height((x + 0.5) / n, (y + 0.5) / n) for x in range(n)] for y in range(n)]
    metres_per_v = layout.metres_per_v()
    normal_rows = []
    for y in range(n):
        row = bytearray()
        v = (y + 0.5) / n
        height_here = HEIGHT * (1 - min(v / V_OUTER[1], 1.0))
        metres_per_u = 2 * math.pi * max(outer_radius(height_here), 0.02)
        for x in range(n):
            dh_du = (heights[y][(x + 1) % n] - heights[y][x - 1]) * n / 2
            dh_dv = (heights[min(y + 1, n - 1)][x] - heights[max(y - 1, 0)][x]) * n / 2
            slope_x = dh_du / metres_per_u  # along the tangent (image right)
            slope_y = -dh_dv / metres_per_v  # along the bitangent (image up, -v)
            length = math.sqrt(slope_x ** 2 + slope_y ** 2 + 1)
            row += bytes((byte(0.5 - 0.5 * slope_x / length), byte(0.5 - 0.5 * slope_y / length),
                          byte(0.5 + 0.5 / length)))
        normal_rows.append(bytes(row))
    write_png(os.path.join(directory, "vase_normal.png"), n, n, normal_rows)


def make_checker(directory, size=256, checks=8):
    """Red and white checks, the Cornell box's red (0.63, 0.065, 0.05) and white (0.725, 0.71, 0.68), sRGB; the
    top-left check is red."""
    red = bytes(srgb_encode(c) for c in (0.63, 0.065, 0.05))
    white = bytes(srgb_encode(c) for c in (0.725, 0.71, 0.68))
    step = size // checks
    rows = [b"".join(red if (x // step + y // step) % 2 == 0 else white for x in range(size)) for y in range(size)]
    write_png(os.path.join(directory, "checker_red_white.png"), size, size, rows)


# ---- glTF ------------------------------------------------------------------------------------------------------


def write_gltf(directory, positions, normals, uvs, tangents, triangles):
    def pack(fmt, items):
        return b"".join(struct.pack(fmt, *item) for item in items)

    rounded = lambda items, digits: [tuple(round(x, digits) for x in item) for item in items]
    positions = rounded(positions, 7)
    normals = [tuple(x / math.sqrt(dot(n, n)) for x in n) for n in normals]
    parts = [
        ("POSITION", pack("<3f", positions), "VEC3", 5126),
        ("NORMAL", pack("<3f", rounded(normals, 7)), "VEC3", 5126),
        ("TEXCOORD_0", pack("<2f", rounded(uvs, 7)), "VEC2", 5126),
        ("TANGENT", pack("<4f", rounded(tangents, 7)), "VEC4", 5126),
    ]
    index_type, index_fmt = (5123, "<3H") if len(positions) < 65536 else (5125, "<3I")
    indices = pack(index_fmt, triangles)
    data = bytearray()
    buffer_views, accessors, attributes = [], [], {}
    for name, blob, kind, component in parts:
        buffer_views.append({"buffer": 0, "byteOffset": len(data), "byteLength": len(blob), "target": 34962})
        accessor = {"bufferView": len(buffer_views) - 1, "componentType": component, "count": len(positions),
                    "type": kind}
        if name == "POSITION":
            accessor["min"] = [min(p[i] for p in positions) for i in range(3)]
            accessor["max"] = [max(p[i] for p in positions) for i in range(3)]
        accessors.append(accessor)
        attributes[name] = len(accessors) - 1
        data += blob
    buffer_views.append({"buffer": 0, "byteOffset": len(data), "byteLength": len(indices), "target": 34963})
    accessors.append({"bufferView": len(buffer_views) - 1, "componentType": index_type,
                      "count": 3 * len(triangles), "type": "SCALAR"})
    data += indices
    with open(os.path.join(directory, "vase.bin"), "wb") as f:
        f.write(data)
    gltf = {
        "asset": {"version": "2.0", "generator": "deltagi scripts/make-textured-example.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "vase", "mesh": 0}],
        "meshes": [{"name": "vase", "primitives": [
            {"attributes": attributes, "indices": len(accessors) - 1, "material": 0, "mode": 4}]}],
        "materials": [{
            "name": "glazed_gilded",
            "pbrMetallicRoughness": {
                "baseColorTexture": {"index": 0},
                "metallicRoughnessTexture": {"index": 1},
                "metallicFactor": 1.0,
                "roughnessFactor": 1.0,
            },
            "normalTexture": {"index": 2, "scale": 1.0},
        }],
        "textures": [{"sampler": 0, "source": i} for i in range(3)],
        "images": [{"uri": "vase_basecolor.png"}, {"uri": "vase_metallic_roughness.png"},
                   {"uri": "vase_normal.png"}],
        "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 33071}],
        "buffers": [{"uri": "vase.bin", "byteLength": len(data)}],
        "bufferViews": buffer_views,
        "accessors": accessors,
    }
    with open(os.path.join(directory, "vase.gltf"), "w") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    directory = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "examples", "textured")
    os.makedirs(directory, exist_ok=True)
    positions, normals, uvs, tangents, triangles, runs = build_mesh()
    write_gltf(directory, positions, normals, uvs, tangents, triangles)
    make_checker(directory)
    make_textures(directory, Layout(runs))
    print(f"make-textured-example.py: {len(triangles)} triangles, {len(positions)} vertices -> {directory}")


if __name__ == "__main__":
    main()
