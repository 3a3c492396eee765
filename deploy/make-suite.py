#!/usr/bin/env python3
"""Writes the workbench's scene suite into deploy/data (docs/results/workbench.md):

  gallery.wrl          a museum hall: 31 objects of very different sizes (a 1.8 m bunny, a horse,
                       the Nefertiti bust: 69k-100k triangles each; a 0.15 m Suzanne), DEF/USE
                       instancing (pedestals, columns, a pair of teapots), two LOD nodes with
                       imposter levels in the pattern of the paper's Figure 10, a flat object
                       (woody.obj, z = 0 for every vertex) and a 2 cm thin painting, primitives.
  city.wrl             a city grid: 1,024 buildings and 256 kiosks (1,280 Box instances, 8
                       DEF'd shapes USEd), 320 m across: culling and reuse matter.
  parts-field.wrl      70 instances (one DEF'd Shape USEd) of the generated multi-manifold model
                       of the hybrid experiments, scattered-parts-300.ply (300 separate closed
                       parts, 96,000 triangles), which deploy/compare writes beside a copy of the
                       scene with `thinlod-simplifier parts` (the case's "generate").
  paper-walk.trace     the paper's flight path through paper-room.wrl, 120 poses over 11.9 s
                       (0.1 s apart) instead of 72 s, so a live run takes 12 s.
  gallery-tour.trace   a walk down the hall at about 0.6 m/s, looking left and right, 12 s.
  gallery-fast.trace   a fast walk (1.3 m/s) with sudden turns (90-180 degrees in 0.2-0.3 s), 10 s.
  city-walk.trace      a walk along an avenue at 1.4 m/s with a turn at a crossing, 12 s.
  parts-fly.trace      a flight into the parts field (the path of bench_hybrid_flythrough), 10 s.
  textured.wrl         textured objects from the Debian package assimp-testmodels: six Collada
                       ducks (duckCM.tga) and six glTF boxes (CesiumLogoFlat.png) in two rows 5 m apart,
                       Inline'd with their ImageTexture; the case runs with --models-dir
                       /usr/share/assimp/models (suite.json "models").
  textured-walk.trace  a walk past the two rows at 0.8 m/s, 10 s.
  court.wrl            a sculpture court (made after session 16's tuning of the budget fill, to
                       test it untouched): eight models on pedestals on a 4 m ring, six columns,
                       a fountain of primitives in the middle, a 1.8 m bunny outside the ring.
  court-walk.trace     120 poses 0.1 s apart: once around the court at 0.7 m/s, looking ahead
                       with glances inwards and outwards (up to 2.8 rad/s).
  aerobic-class.wrl    the ASLOD paper's "aerobic class" (issue 18): three skinned, animated
                       Testwuson.X figures of assimp-testmodels 3 m apart, the outer two playing
                       Wuson_Run, the middle one Wuson_Walk (the backbone plays every clip on
                       pose time, no animationOffset: the Run figures move in step); --models-dir /usr/share/assimp/models/X.
  aerobic-class.trace  120 poses 0.1 s apart: a walk at 0.8 m/s into the class, close to the
                       left figure (the right one leaves the view), then a turn of about 110
                       degrees to the right figure while walking towards it.

Model sizes are read from the model files in --models-dir (default ../shared/models), so the
scale factors written into the scenes are exact; the scenes name the models by file name only
(the daemons find them through --models-dir). Deterministic: fixed seeds, no time stamps.
`--only-city --city-blocks 90 --out DIR` writes a city of 10,125 instances alone (scale runs).

Usage: deploy/make-suite.py [--models-dir DIR] [--out DIR]
"""
import argparse
import importlib.util
import math
import os
import random
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def model_bounds(path):
    """Axis-aligned bounds (lo, hi) of an OBJ or binary/ASCII PLY file's vertices."""
    lo, hi = [math.inf] * 3, [-math.inf] * 3

    def extend(p):
        for k in range(3):
            lo[k] = min(lo[k], p[k])
            hi[k] = max(hi[k], p[k])

    if path.endswith(".obj"):
        with open(path, errors="replace") as f:
            for line in f:
                if line.startswith("v "):
                    extend([float(x) for x in line.split()[1:4]])
        return lo, hi
    with open(path, "rb") as f:
        fmt, count, props = None, 0, []
        in_vertex = False
        while True:
            line = f.readline().decode("ascii", "replace").strip()
            if line.startswith("format"):
                fmt = line.split()[1]
            elif line.startswith("element"):
                in_vertex = line.split()[1] == "vertex"
                if in_vertex:
                    count = int(line.split()[2])
            elif line.startswith("property") and in_vertex:
                props.append(line.split()[1])
            elif line == "end_header":
                break
        sizes = {"float": 4, "float32": 4, "double": 8, "float64": 8}
        if fmt == "ascii":
            for _ in range(count):
                extend([float(x) for x in f.readline().split()[:3]])
            return lo, hi
        if fmt != "binary_little_endian" or any(p not in sizes for p in props):
            raise SystemExit(f"make-suite: {path}: unsupported PLY layout {fmt} {props}")
        codes = "".join("f" if sizes[p] == 4 else "d" for p in props)
        stride = struct.calcsize("<" + codes)
        data = f.read(count * stride)
        for i in range(count):
            extend(struct.unpack_from("<" + codes, data, i * stride)[:3])
    return lo, hi


def fmt(*values):
    return " ".join(f"{v:.6g}" for v in values)


def material(rgb):
    return f"appearance Appearance {{ material Material {{ diffuseColor {fmt(*rgb)} }} }}"


class Gallery:
    """A hall x in [0, 20], z in [0, 10] (metres, y up); objects along both long walls."""

    # name: (file, up axis of the model, height in the hall (m), colour)
    MODELS = {
        "bunny": ("stanford-bunny.obj", "y", 1.8, (0.85, 0.8, 0.7)),
        "horse": ("horse.ply", "z", 1.1, (0.55, 0.4, 0.3)),
        "nefertiti": ("nefertiti.obj", "z", 0.55, (0.8, 0.65, 0.4)),
        "cow": ("cow.obj", "y", 0.3, (0.8, 0.75, 0.65)),
        "spot": ("spot.obj", "y", 0.35, (0.9, 0.55, 0.3)),
        "teapot": ("teapot.obj", "y", 0.22, (0.3, 0.55, 0.8)),
        "suzanne": ("suzanne.obj", "y", 0.15, (0.7, 0.3, 0.6)),
        "cheburashka": ("cheburashka.obj", "y", 0.35, (0.6, 0.45, 0.3)),
        "fandisk": ("fandisk.obj", "y", 0.3, (0.6, 0.6, 0.65)),
        "woody": ("woody.obj", "y", 1.0, (0.8, 0.5, 0.25)),
    }

    def __init__(self, models_dir):
        self.models_dir = models_dir
        self.parts = []
        self.objects = 0

    def fitted(self, name, base, yaw_deg, shape_def=None, use=None):
        """Transform nest placing model `name` with its bottom centre at `base`, turned by
        `yaw_deg` about +y; the Shape is DEF'd as `shape_def` (default the capitalised name),
        or `USE use` of an earlier one. Returns the VRML text and the Shape's DEF name."""
        file, up, height, rgb = self.MODELS[name]
        lo, hi = model_bounds(os.path.join(self.models_dir, file))
        centre = [(a + b) / 2 for a, b in zip(lo, hi)]
        if up == "y":
            bottom = (centre[0], lo[1], centre[2])
            fix = "0 0 1 0"
            extent = hi[1] - lo[1]
        else:  # z up: rotate -90 degrees about x, (x, y, z) -> (x, z, -y)
            bottom = (centre[0], centre[1], lo[2])
            fix = "1 0 0 -1.5708"
            extent = hi[2] - lo[2]
        scale = height / extent
        shape_def = shape_def or name.capitalize()
        shape = (f"USE {use}" if use else
                 f"DEF {shape_def} Shape {{ {material(rgb)} geometry Inline {{ url \"{file}\" }} }}")
        text = (f"Transform {{ translation {fmt(*base)} rotation 0 1 0 {math.radians(yaw_deg):.6g}\n"
                f"  children Transform {{ rotation {fix} scale {fmt(scale, scale, scale)}\n"
                f"    children Transform {{ translation {fmt(*[-c for c in bottom])}\n"
                f"      children {shape} }} }} }}")
        return text, shape_def

    def add(self, comment, text, objects):
        self.parts.append(f"# {comment}\n{text}\n")
        self.objects += objects

    def add_columns(self, centres, radius, height, rgb):
        """Cylinders at `centres` (x, y, z): the first DEF'd Column, the others USE it."""
        for i, centre in enumerate(centres):
            column = ("DEF Column Shape { " + material(rgb) +
                      f" geometry Cylinder {{ radius {radius:g} height {height:g} }} }}"
                      if i == 0 else "USE Column")
            self.add(f"column {i} ({'DEF' if i == 0 else 'USE'})",
                     f"Transform {{ translation {fmt(*centre)} children {column} }}", 1)

    def write_file(self, path, title, extent, viewpoint, light):
        """The scene file: header lines, the Viewpoint and DirectionalLight given, the parts."""
        with open(path, "w") as f:
            f.write("#VRML V2.0 utf8\n")
            f.write(f"# Workbench {title} (made by deploy/make-suite.py; do not edit by hand).\n")
            f.write(f"# {extent}, y up; {self.objects} drawable objects.\n")
            f.write("# Models are named by file name and found through --models-dir.\n\n")
            f.write(viewpoint + "\n")
            f.write(light + "\n\n")
            f.write("".join(self.parts))
        return self.objects

    def lod_statue(self, name, base, yaw_deg, far):
        """The paper's Figure 10: level 0 the Shape, level 1 a SimpleImposter of it (only
        beyond `far` metres), level 2 a MeshedImposter of it, everywhere. The imposter levels
        USE the placed model (its whole Transform nest), so all three levels are the same
        geometry in the same place and the backbone schedules them as one object
        (docs/backbone.md "Imposter nodes"); a USE of the bare Shape would put an unscaled
        model at the LOD's origin."""
        statue, shape = self.fitted(name, (0, 0, 0), 0)
        placed = f"{shape}Placed"
        self.add(f"{name}: LOD with imposter levels (Figure 10 pattern)",
                 f"Transform {{ translation {fmt(*base)} rotation 0 1 0 {math.radians(yaw_deg):.6g}\n"
                 f"  children LOD {{\n"
                 f"    level [\n      DEF {placed} {statue}\n"
                 f"      SimpleImposter {{ children [ USE {placed} ] }}\n"
                 f"      MeshedImposter {{ children [ USE {placed} ] }}\n    ]\n"
                 f"    range [ ConicRange {{}}, ConicRange {{ distance {far:g} 1000 }}, ConicRange {{}} ]\n"
                 f"  }} }}", 3)

    def on_pedestal(self, name, x, z, yaw_deg, shape_def=None, use=None):
        pedestal = ("DEF Pedestal Shape { " + material((0.45, 0.45, 0.5)) +
                    " geometry Box { size 0.6 1 0.6 } }") if not self.pedestals else "USE Pedestal"
        self.add(f"pedestal ({'USE' if self.pedestals else 'DEF'})",
                 f"Transform {{ translation {fmt(x, 0.5, z)} children {pedestal} }}", 1)
        self.pedestals += 1
        text, shape = self.fitted(name, (x, 1.0, z), yaw_deg, shape_def, use)
        self.add(f"{name} on its pedestal" + (f" (USE {use})" if use else ""), text, 1)
        return shape

    def write(self, path):
        self.pedestals = 0
        self.lod_statue("bunny", (4.0, 0.0, 8.3), 200, 6)
        self.add("plinth of the horse", "Transform { translation 10 0.25 8.3 children Shape { " +
                 material((0.4, 0.4, 0.45)) + " geometry Box { size 2.2 0.5 1.2 } } }", 1)
        self.lod_statue("horse", (10.0, 0.5, 8.3), 90, 6)
        for name, x, z in (("cow", 6.5, 1.7), ("suzanne", 9.0, 1.7), ("spot", 11.5, 1.7),
                           ("cheburashka", 14.0, 1.7), ("fandisk", 1.5, 8.3),
                           ("nefertiti", 16.0, 8.3), ("teapot", 3.5, 1.7)):
            self.on_pedestal(name, x, z, 180 if z > 5 else 20)
        # The teapot's twin shares its Shape (and mesh) through USE, placed on its own.
        self.on_pedestal("teapot", 17.5, 1.7, -30, use="Teapot")
        woody, _ = self.fitted("woody", (19.9, 1.0, 5.0), -90)
        self.add("woody.obj: a flat gingerbread man (every z = 0) on the end wall, facing -x",
                 woody, 1)
        self.add("a painting 2 cm thin on the back wall",
                 "Transform { translation 10 1.9 9.95 children Shape { " +
                 material((0.75, 0.2, 0.15)) + " geometry Box { size 2.4 1.4 0.02 } } }", 1)
        self.add_columns([(x, 1.5, 5.0 + (1.2 if i % 2 else -1.2))
                          for i, x in enumerate((2.5, 7.5, 12.5, 17.5))], 0.25, 3, (0.85, 0.85, 0.8))
        self.add("a sculpture of primitives: a cone with a sphere on top",
                 "Transform { translation 13 0.6 5 children [\n"
                 "  Shape { " + material((0.2, 0.6, 0.35)) +
                 " geometry Cone { bottomRadius 0.45 height 1.2 } }\n"
                 "  Transform { translation 0 0.85 0 children Shape { " +
                 material((0.9, 0.8, 0.2)) + " geometry Sphere { radius 0.3 } } } ] }", 2)
        return self.write_file(
            path, "gallery", "A hall x [0, 20], z [0, 10] m",
            'Viewpoint { description "entrance" position 0.5 1.6 5 '
            'orientation 0 1 0 -1.5708 fieldOfView 0.9 }',
            "DirectionalLight { direction 0.3 -1.0 -0.5 intensity 0.9 ambientIntensity 0.3 }")


def write_city(path, seed=12, blocks=32):
    """blocks^2 buildings on a grid of 10 m blocks and (blocks/2)^2 kiosks along the avenues
    (the suite's city: 32, 1,024 buildings and 256 kiosks)."""
    rng = random.Random(seed)
    colours = [(0.6, 0.6, 0.65), (0.7, 0.55, 0.45), (0.45, 0.5, 0.6), (0.75, 0.7, 0.6)]
    half = 5 * blocks  # the grid spans x, z in [-half, half]
    lines = ["#VRML V2.0 utf8",
             "# Workbench city (made by deploy/make-suite.py; do not edit by hand).",
             f"# {blocks} x {blocks} blocks of 10 m (x, z in [-{half}, {half}]), streets 4 m wide "
             "at x, z = 10 k;",
             f"# {blocks * blocks:,} buildings (4 DEF'd unit boxes USEd with their own scale) and "
             f"{(blocks // 2) ** 2:,} kiosks.",
             'Viewpoint { description "avenue" position 0 1.7 150 fieldOfView 0.9 }',
             "DirectionalLight { direction 0.4 -1.0 -0.3 intensity 0.9 ambientIntensity 0.3 }"]
    count = 0
    defined = set()
    for i in range(blocks):
        for j in range(blocks):
            x = -half + 5 + 10 * i
            z = -half + 5 + 10 * j
            k = (i * 7 + j * 3) % 4
            h = rng.choice((4, 6, 9, 12, 18, 25)) * (0.8 + 0.4 * rng.random())
            w, d = 6 * (0.8 + 0.2 * rng.random()), 6 * (0.8 + 0.2 * rng.random())
            shape = (f"USE Building{k}" if k in defined else
                     f"DEF Building{k} Shape {{ {material(colours[k])} geometry Box {{ size 1 1 1 }} }}")
            defined.add(k)
            lines.append(f"Transform {{ translation {fmt(x, h / 2, z)} scale {fmt(w, h, d)} "
                         f"children {shape} }}")
            count += 1
    kiosk_colours = [(0.2, 0.6, 0.3), (0.8, 0.3, 0.2), (0.9, 0.8, 0.3), (0.3, 0.4, 0.8)]
    kiosks = 0
    for a in range(blocks // 2):
        for b in range(blocks // 2):
            x = -half + 20 * a + 10 + (1.5 if b % 2 else -1.5)
            z = -half + 5 + 20 * b
            k = (a + b) % 4
            shape = (f"USE Kiosk{k}" if ("kiosk", k) in defined else
                     f"DEF Kiosk{k} Shape {{ {material(kiosk_colours[k])} geometry Box {{ size 1.2 2.2 1.2 }} }}")
            defined.add(("kiosk", k))
            lines.append(f"Transform {{ translation {fmt(x, 1.1, z)} children {shape} }}")
            kiosks += 1
    # The first DEF of each building kind must come before its USEs.
    text = "\n".join(lines) + "\n"
    for k in range(4):
        d = text.find(f"DEF Building{k} ")
        u = text.find(f"USE Building{k}")
        assert d != -1 and (u == -1 or d < u), f"Building{k}"
        d = text.find(f"DEF Kiosk{k} ")
        u = text.find(f"USE Kiosk{k}")
        assert d != -1 and (u == -1 or d < u), f"Kiosk{k}"
    with open(path, "w") as f:
        f.write(text)
    return count + kiosks


PARTS_MODEL = "scattered-parts-300.ply"
PARTS_PER_ROW, PARTS_SPACING = 10, 1.6


def write_parts_field(path, count=70, seed=11):
    """`count` instances of the generated multi-manifold model (a unit box) in rows of 10 along +x,
    rows 1.6 apart along -z, random yaw and size 0.8-1.2: the layout of bench_hybrid_flythrough."""
    rng = random.Random(seed)
    lines = ["#VRML V2.0 utf8",
             "# Workbench parts field (made by deploy/make-suite.py; do not edit by hand).",
             f"# {count} instances of {PARTS_MODEL} (generateScatteredParts(300, 2, 7): 300 closed",
             "# parts in a unit box), written beside a copy of this scene by deploy/compare.",
             'Viewpoint { description "front" position -2 0.9 1.5 fieldOfView 1.047 }',
             "DirectionalLight { direction 0.3 -1.0 -0.4 intensity 0.9 ambientIntensity 0.3 }"]
    for i in range(count):
        row, column = divmod(i, PARTS_PER_ROW)
        scale = 0.8 + 0.4 * rng.random()
        at = (PARTS_SPACING * column + 0.4 * (rng.random() - 0.5), 0.3 * (rng.random() - 0.5),
              -PARTS_SPACING * row + 0.4 * (rng.random() - 0.5))
        yaw = 2 * math.pi * rng.random()
        shape = ("USE Parts" if i else
                 f"DEF Parts Shape {{ {material((0.8, 0.6, 0.4))} "
                 f"geometry Inline {{ url \"{PARTS_MODEL}\" }} }}")
        lines.append(f"Transform {{ translation {fmt(*at)} rotation 0 1 0 {yaw:.6g} "
                     f"scale {fmt(scale, scale, scale)}\n"
                     f"  children Transform {{ translation -0.5 -0.5 -0.5 children {shape} }} }}")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return count


def parts_fly(count=70, frames=100, dt=0.1):
    """bench_hybrid_flythrough's path: from the field's front-left corner, descending diagonally to
    past its middle, always looking at its far corner."""
    length = PARTS_SPACING * (min(count, PARTS_PER_ROW) - 1)
    depth = PARTS_SPACING * ((count + PARTS_PER_ROW - 1) // PARTS_PER_ROW)
    start, end = (-2.0, 1.2, 2.5), (0.7 * length, 0.5, -0.6 * depth)
    poses = []
    for k in range(frames):
        u = k / (frames - 1)
        eye = tuple(a + (b - a) * u for a, b in zip(start, end))
        target = (length + 1.0, 0.0, -depth - 1.0 + 2.0 * math.sin(2 * math.pi * u))
        poses.append((round(k * dt, 6), eye, target))
    return poses


class Court(Gallery):
    """A sculpture court (made after the shading-fill tuning of session 16, to test it on a
    scene it was not tuned on): eight models on pedestals on a ring of radius 4 m around
    (6, 0, 6), six columns on a ring of 2.4 m, a fountain of primitives in the middle."""

    def write(self, path):
        self.pedestals = 0
        cx, cz = 6.0, 6.0
        ring = ("cheburashka", "spot", "nefertiti", "cow", "teapot", "fandisk", "suzanne", "horse")
        for k, name in enumerate(ring):
            a = 2 * math.pi * k / len(ring)
            x, z = cx + 4.0 * math.cos(a), cz + 4.0 * math.sin(a)
            # facing the centre: the model's +z towards (cx, cz)
            yaw = math.degrees(math.atan2(cx - x, cz - z))
            self.on_pedestal(name, x, z, yaw)
        ring_angles = [2 * math.pi * (k + 0.5) / 6 for k in range(6)]
        self.add_columns([(cx + 2.4 * math.cos(a), 1.3, cz + 2.4 * math.sin(a)) for a in ring_angles],
                         0.18, 2.6, (0.8, 0.8, 0.78))
        self.add("the fountain: a basin (cylinder), a sphere on a cone",
                 f"Transform {{ translation {fmt(cx, 0.2, cz)} children [\n"
                 "  Shape { " + material((0.5, 0.55, 0.6)) +
                 " geometry Cylinder { radius 0.9 height 0.4 } }\n"
                 "  Transform { translation 0 0.7 0 children Shape { " + material((0.3, 0.5, 0.7)) +
                 " geometry Cone { bottomRadius 0.3 height 1.0 } } }\n"
                 "  Transform { translation 0 1.35 0 children Shape { " + material((0.9, 0.85, 0.3)) +
                 " geometry Sphere { radius 0.25 } } } ] }", 3)
        bunny, _ = self.fitted("bunny", (cx + 7.0, 0.0, cz), -90)
        self.add("a 1.8 m bunny outside the ring, facing the court", bunny, 1)
        return self.write_file(
            path, "sculpture court", "A ring of radius 4 m around (6, 0, 6)",
            'Viewpoint { description "court" position 6 1.6 0.5 fieldOfView 0.9 }',
            "DirectionalLight { direction -0.4 -1.0 -0.3 intensity 0.9 ambientIntensity 0.3 }")


def write_trace(path, title, poses, fov_deg):
    """poses: [(t, eye, target)]."""
    with open(path, "w") as f:
        f.write("# thinlod-trace 1\n")
        f.write(f"# {title} (made by deploy/make-suite.py)\n")
        f.write("# time_s  px py pz  lookat tx ty tz  fov_deg\n")
        for t, e, g in poses:
            f.write(f"{t:.3f} {fmt(*e)} lookat {fmt(*g)} {fov_deg:g}\n")


def max_speed(poses):
    return max(math.dist(a[1], b[1]) / (b[0] - a[0]) for a, b in zip(poses, poses[1:]))


def along(points, speed, dt, heading_of):
    """Walks the polyline `points` (x, y, z) at `speed` m/s, a pose every `dt` s; the look
    direction at time t is heading_of(t, position, segment direction) -> target."""
    seg_lengths = [math.dist(a, b) for a, b in zip(points, points[1:])]
    total = sum(seg_lengths)
    poses, t = [], 0.0
    while t * speed <= total + 1e-9:
        s, k = t * speed, 0
        while k < len(seg_lengths) - 1 and s > seg_lengths[k]:
            s -= seg_lengths[k]
            k += 1
        a, b = points[k], points[k + 1]
        u = min(s / seg_lengths[k], 1.0)
        p = tuple(a[i] + (b[i] - a[i]) * u for i in range(3))
        direction = tuple((b[i] - a[i]) / seg_lengths[k] for i in range(3))
        poses.append((round(t, 6), p, heading_of(t, p, direction)))
        t += dt
    return poses


def yaw_target(p, yaw_deg, down=0.25):
    """A look-at target 1 m from p at yaw (0 = +x, 90 = -z, counter-clockwise seen from +y)."""
    a = math.radians(yaw_deg)
    return (p[0] + math.cos(a), p[1] - down, p[2] - math.sin(a))


def smoothstep(x):
    x = min(max(x, 0.0), 1.0)
    return x * x * (3 - 2 * x)


def yaw_schedule(keys):
    """keys: [(t, yaw_deg)]; yaw holds between keys and turns in the key's duration."""
    def yaw(t):
        value = keys[0][1]
        for start, duration, target in keys[1:]:
            if t >= start:
                value = value + (target - value) * smoothstep((t - start) / duration)
        return value
    return yaw


def write_textured(path):
    """Two rows of textured objects from assimp-testmodels (urls under /usr/share/assimp/models;
    each ImageTexture url is relative to the Inline file that names it)."""
    duck = ('Shape { appearance Appearance { material Material { diffuseColor 1 1 1 } '
            'texture ImageTexture { url "duckCM.tga" } } geometry Inline { url "Collada/duck.dae" } }')
    box = ('Shape { appearance Appearance { material Material { diffuseColor 1 1 1 } '
           'texture ImageTexture { url "CesiumLogoFlat.png" } } '
           'geometry Inline { url "glTF2/BoxTextured-glTF/BoxTextured.gltf" } }')
    lines = ["#VRML V2.0 utf8", "# Textured scene of the workbench (made by deploy/make-suite.py):",
             "# assimp-testmodels' Collada duck and glTF textured box, --models-dir /usr/share/assimp/models",
             "DirectionalLight { direction -0.3 -1 -0.5 }",
             "DEF DUCK Transform { translation 0 0 0 rotation 0 1 0 0.6 children [ " + duck + " ] }",
             "DEF BOX Transform { translation 0 0.5 5 rotation 0 1 0 0.4 children [ " + box + " ] }"]
    for i in range(1, 6):
        lines.append(f"Transform {{ translation {2.5 * i:g} 0 0 rotation 0 1 0 {0.5 * i:g} children USE DUCK }}")
        lines.append(f"Transform {{ translation {2.5 * i:g} 0 {0.4 * (i % 2):g} children USE BOX }}")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return 12


AEROBIC_FIGURES = ((-3.0, 0.0, 0.35, "Wuson_Run"), (0.0, -1.0, 0.0, "Wuson_Walk"),
                   (3.0, 0.0, -0.35, "Wuson_Run"))  # x, z, yaw (rad), clip


def write_aerobic(path):
    """Three animated, skinned Testwuson.X figures in a row (ASLOD's aerobic class)."""
    lines = ["#VRML V2.0 utf8",
             "# ASLOD aerobic class (made by deploy/make-suite.py; do not edit by hand): three",
             "# skinned, animated Testwuson.X figures (assimp-testmodels), --models-dir",
             "# /usr/share/assimp/models/X; docs/results/aslod.md.",
             'Viewpoint { description "front" position 0 1.4 7 fieldOfView 0.9 }',
             "DirectionalLight { direction 0.3 -1 -0.6 intensity 0.9 ambientIntensity 0.3 }"]
    for x, z, yaw, clip in AEROBIC_FIGURES:
        lines.append(f"Transform {{ translation {fmt(x, 0, z)} rotation 0 1 0 {yaw:g} children [\n"
                     f"  Inline {{ url \"Testwuson.X\" animation \"{clip}\" }} ] }}")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return len(AEROBIC_FIGURES)


def aerobic_walk(frames=120, dt=0.1):
    """A walk at 0.8 m/s from 7.5 m in front of the class to 2.7 m from the left figure (the
    right one leaves the view), then a turn of about 110 degrees to the right figure while
    walking towards it; look-at targets blend with smoothstep: the class centre, the left figure
    (3.0-5.5 s), the right figure (8.0-10.5 s)."""
    points = [(0.0, 1.5, 7.5), (-2.0, 1.5, 3.0), (-1.0, 1.5, 1.8), (2.0, 1.5, 2.5)]
    keys = [(3.0, 2.5, (-3.0, 0.8, 0.0)), (8.0, 2.5, (3.0, 0.8, 0.0))]

    def target(t, p, d):
        value = (0.0, 0.8, -0.3)
        for start, duration, goal in keys:
            if t >= start:
                u = smoothstep((t - start) / duration)
                value = tuple(a + (b - a) * u for a, b in zip(value, goal))
        return value
    return along(points, 0.8, dt, target)[:frames]


def max_angular_speed(poses):
    """Largest turn of the view direction between two poses, rad/s."""
    def direction(p):
        d = [b - a for a, b in zip(p[1], p[2])]
        n = math.sqrt(sum(c * c for c in d))
        return [c / n for c in d]
    return max(math.acos(max(-1.0, min(1.0, sum(x * y for x, y in zip(direction(a), direction(b))))))
               / (b[0] - a[0]) for a, b in zip(poses, poses[1:]))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--models-dir", default=os.path.join(HERE, "..", "..", "shared", "models"))
    parser.add_argument("--out", default=os.path.join(HERE, "data"))
    parser.add_argument("--city-blocks", type=int, default=32,
                        help="side of the city's grid of blocks (default 32: 1,280 instances; "
                             "90 gives 10,125, the scale runs of docs/results/scale.md)")
    parser.add_argument("--only-city", action="store_true",
                        help="write city.wrl only (with --city-blocks, for scale runs)")
    args = parser.parse_args()
    if not 2 <= args.city_blocks <= 1000:
        parser.error("--city-blocks must be in [2, 1000]")
    os.makedirs(args.out, exist_ok=True)
    if args.only_city:
        instances = write_city(os.path.join(args.out, "city.wrl"), blocks=args.city_blocks)
        print(f"make-suite: city {instances} instances in {args.out}")
        return

    objects = Gallery(args.models_dir).write(os.path.join(args.out, "gallery.wrl"))
    instances = write_city(os.path.join(args.out, "city.wrl"), blocks=args.city_blocks)
    parts = write_parts_field(os.path.join(args.out, "parts-field.wrl"))
    textured = write_textured(os.path.join(args.out, "textured.wrl"))

    # The paper's flight, same key frames and spline, 0.1 s per pose.
    spec = importlib.util.spec_from_file_location("paper", os.path.join(HERE, "make-paper-trace.py"))
    paper = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(paper)
    frames = 120
    scale = (paper.FRAMES - 1) / (frames - 1)
    walk = [(0.1 * i, paper.spline(1, i * scale), paper.spline(2, i * scale)) for i in range(frames)]
    write_trace(os.path.join(args.out, "paper-walk.trace"),
                f"the paper's flight through paper-room.wrl, {frames} poses 0.1 s apart "
                f"(max {max_speed(walk):.2f} m/s)", walk, paper.FOV_DEG)

    # Gallery tour: down the aisle (z = 5) at 0.6 m/s, turning the head to each side.
    tour_points = [(0.5, 1.6, 5.0), (7.7, 1.6, 5.0)]
    look = yaw_schedule([(0, 0), (1.0, 2.0, 60), (4.0, 2.5, -60), (7.5, 2.5, 45), (10.5, 1.5, 0)])
    tour = along(tour_points, 0.6, 0.1, lambda t, p, d: yaw_target(p, look(t)))[:120]
    write_trace(os.path.join(args.out, "gallery-tour.trace"),
                f"gallery tour at 0.6 m/s, {len(tour)} poses", tour, 60)

    # Fast walk: 1.3 m/s along the aisle and back, with sudden turns.
    fast_points = [(0.5, 1.6, 5.0), (12.0, 1.6, 5.0), (12.0, 1.6, 3.0), (4.0, 1.6, 3.0)]
    snap = yaw_schedule([(0, 0), (1.5, 0.2, 90), (2.5, 0.25, -90), (4.0, 0.2, 0),
                         (6.0, 0.3, 180), (7.5, 0.2, 90), (8.5, 0.25, 200)])
    fast = along(fast_points, 1.3, 1 / 15, lambda t, p, d: yaw_target(p, snap(t), 0.15))[:150]
    write_trace(os.path.join(args.out, "gallery-fast.trace"),
                f"fast walk through the gallery at 1.3 m/s with sudden turns, {len(fast)} poses",
                fast, 60)

    # City: along the avenue x = 0 (a street) at 1.4 m/s, turning right at the crossing z = 140.
    city_points = [(0.0, 1.7, 150.0), (0.0, 1.7, 140.0), (10.0, 1.7, 140.0)]
    heading = yaw_schedule([(0, 90), (7.0, 1.2, 0)])
    city = along(city_points, 1.4, 0.1, lambda t, p, d: yaw_target(p, heading(t), 0.05))[:120]
    write_trace(os.path.join(args.out, "city-walk.trace"),
                f"city walk at 1.4 m/s with a turn at a crossing, {len(city)} poses", city, 60)

    fly = parts_fly(parts)
    write_trace(os.path.join(args.out, "parts-fly.trace"),
                f"flight into the parts field, {len(fly)} poses (max {max_speed(fly):.2f} m/s)",
                fly, 60)

    # Textured walk: between the rows (ducks at z = 0, boxes at z = 5), looking at each side.
    textured_points = [(-1.5, 1.5, 2.5), (13.5, 1.5, 2.5)]
    sides = yaw_schedule([(0, -30), (2.0, 1.0, 60), (5.0, 1.0, -60), (8.0, 1.0, 40)])
    textured_walk = along(textured_points, 0.8, 0.1, lambda t, p, d: yaw_target(p, sides(t), 0.2))[:100]
    write_trace(os.path.join(args.out, "textured-walk.trace"),
                f"walk between the textured rows at 0.8 m/s, {len(textured_walk)} poses",
                textured_walk, 60)

    # Sculpture court: once around between the columns and the pedestals (radius 3.2 m) at
    # 0.7 m/s, looking at the sculptures ahead and glancing at the fountain and outwards.
    court = Court(args.models_dir).write(os.path.join(args.out, "court.wrl"))
    def court_pose(t):
        a = -math.pi / 2 + 0.7 * t / 3.2
        return (6.0 + 3.2 * math.cos(a), 1.6, 6.0 + 3.2 * math.sin(a)), a
    glance = yaw_schedule([(0, 0), (3.0, 1.0, 70), (6.0, 1.2, -50), (9.5, 1.0, 0)])
    court_walk = []
    for i in range(120):
        t = 0.1 * i
        p, a = court_pose(t)
        forward = math.degrees(-(a + math.pi / 2))  # the walking direction as a yaw
        court_walk.append((round(t, 6), p, yaw_target(p, forward + glance(t), 0.2)))
    write_trace(os.path.join(args.out, "court-walk.trace"),
                f"walk around the sculpture court at 0.7 m/s, {len(court_walk)} poses", court_walk, 60)

    figures = write_aerobic(os.path.join(args.out, "aerobic-class.wrl"))
    aerobic = aerobic_walk()
    write_trace(os.path.join(args.out, "aerobic-class.trace"),
                f"a walk into the aerobic class, {len(aerobic)} poses 0.1 s apart (max "
                f"{max_speed(aerobic):.2f} m/s, {max_angular_speed(aerobic):.2f} rad/s)", aerobic, 60)

    print(f"make-suite: court {court} objects; textured {textured} objects; gallery {objects} objects, city {instances} instances, parts field "
          f"{parts} instances (parts-fly {len(fly)} poses, {max_speed(fly):.2f} m/s); traces: "
          f"paper-walk {len(walk)} ({max_speed(walk):.2f} m/s), gallery-tour {len(tour)} "
          f"({max_speed(tour):.2f} m/s), gallery-fast {len(fast)} ({max_speed(fast):.2f} m/s), "
          f"city-walk {len(city)} ({max_speed(city):.2f} m/s), aerobic-class {figures} figures, "
          f"{len(aerobic)} poses ({max_speed(aerobic):.2f} m/s, {max_angular_speed(aerobic):.2f} rad/s)")


if __name__ == "__main__":
    main()
