#!/usr/bin/env python3
"""Writes deploy/data/paper-flight.trace: the 100-frame flight path of the paper's experiment
(Pasman & Jansen 2002, section 4.2) through deploy/data/paper-room.wrl.

Key frames follow the paper's description: the first sphere leaves the view in the first frames,
the second sphere fills the view around frames 20-30, the cylinder around 45-60, the cow from
frame 65 on. Positions and look-at targets are Catmull-Rom splines through the key frames; the
frame interval is chosen so the viewer never moves faster than MAX_SPEED (the observer speed
bound the backbone plans with), so the prediction is honest.

Usage: deploy/make-paper-trace.py [--frames N] [OUT]
  OUT defaults to deploy/data/paper-flight.trace; --frames samples the same path more finely
  (e.g. 1000 frames for latency runs long enough for a stable p99).
"""
import argparse
import math

FRAMES = 100
MAX_SPEED = 0.095  # m/s, under the demo's 0.1 m/s bound
FOV_DEG = 45.0
# (frame, eye position, look-at target); room layout in docs/scene-format.md
KEYS = [
    (0, (2.00, 1.10, 3.50), (2.00, 0.50, 0.50)),
    (12, (2.25, 0.95, 2.85), (2.90, 0.50, 1.95)),
    (25, (2.55, 0.75, 2.25), (3.30, 0.50, 1.90)),
    (38, (2.10, 0.75, 1.90), (1.20, 0.50, 1.30)),
    (52, (1.45, 0.80, 1.55), (0.80, 0.50, 1.20)),
    (65, (1.75, 0.72, 1.45), (2.00, 0.30, 0.55)),
    (82, (1.95, 0.65, 1.35), (2.05, 0.27, 0.55)),
    (99, (2.05, 0.60, 1.25), (2.06, 0.25, 0.55)),
]


def catmull_rom(p0, p1, p2, p3, t):
    return tuple(
        0.5 * ((2 * b) + (-a + c) * t + (2 * a - 5 * b + 4 * c - d) * t * t +
               (-a + 3 * b - 3 * c + d) * t * t * t)
        for a, b, c, d in zip(p0, p1, p2, p3))


def spline(index, frame):
    for k in range(len(KEYS) - 1):
        f0, f1 = KEYS[k][0], KEYS[k + 1][0]
        if f0 <= frame <= f1:
            pts = [KEYS[max(k - 1, 0)][index], KEYS[k][index], KEYS[k + 1][index],
                   KEYS[min(k + 2, len(KEYS) - 1)][index]]
            return catmull_rom(*pts, (frame - f0) / (f1 - f0))
    raise ValueError(frame)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", nargs="?", default="deploy/data/paper-flight.trace")
    parser.add_argument("--frames", type=int, default=FRAMES, help="poses along the path (>= 2)")
    args = parser.parse_args()
    if args.frames < 2:
        parser.error("--frames must be at least 2")
    out, frames = args.out, args.frames
    # Key frames are numbered on the 100-frame path; more frames sample it more finely.
    scale = (FRAMES - 1) / (frames - 1)
    eyes = [spline(1, i * scale) for i in range(frames)]
    targets = [spline(2, i * scale) for i in range(frames)]
    step = max(math.dist(eyes[i], eyes[i + 1]) for i in range(frames - 1))
    dt = math.ceil(step / MAX_SPEED * 100) / 100  # seconds per frame, rounded up to 10 ms
    with open(out, "w") as f:
        f.write("# thinlod-trace 1\n")
        f.write("# Flight path of the paper's experiment (Pasman & Jansen 2002, section 4.2) through\n")
        f.write("# deploy/data/paper-room.wrl; made by deploy/make-paper-trace.py.\n")
        f.write(f"# {frames} frames, {dt:.2f} s apart: the viewer never exceeds {MAX_SPEED} m/s.\n")
        f.write("# time_s  px py pz  lookat tx ty tz  fov_deg\n")
        for i in range(frames):
            e, t = eyes[i], targets[i]
            f.write(f"{i * dt:.2f} {e[0]:.4f} {e[1]:.4f} {e[2]:.4f} lookat "
                    f"{t[0]:.4f} {t[1]:.4f} {t[2]:.4f} {FOV_DEG:g}\n")
    print(f"wrote {out}: {frames} frames, dt {dt:.2f} s, max step {step:.4f} m")


if __name__ == "__main__":
    main()
