"""A small deploy/compare results folder written from scratch (no daemons): two cases, two
schedulers each, frames.csv / decisions.csv / run.json / frontend-summary.json and PNG dumps."""
import json
import os
import struct
import zlib

FRAME_HEADER = ("frame,time_s,polygons,link_bytes,target_accuracy,snr_db,psnr_db,render_ms,"
                "pose_to_frame_ms,update_latency_ms,plan,draw_calls,uploaded_bytes,reference_ms,"
                "wait_ms,updates_received,updates_rejected,lockstep_timeout,shown_at_ms,"
                "visible_objects,missing_objects,blank")


def png_bytes(width, height, pixel):
    """An RGBA PNG whose pixel (x, y) is pixel(x, y) -> (r, g, b, a)."""
    raw = b"".join(b"\x00" + b"".join(bytes(pixel(x, y)) for x in range(width))
                   for y in range(height))
    chunk = lambda kind, data: (struct.pack(">I", len(data)) + kind + data +
                                struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def frame_row(frame, time_s, polygons, link, snr, update, shown, visible, missing, blank):
    return (f"{frame},{time_s},{polygons},{link},10,{snr},{'' if snr == '' else 30},1.0,2.0,"
            f"{update},{frame},1,0,20,0.1,1,0,0,{shown},{visible},{missing},{blank}")


def write_run(out, case, scheduler, budget, rows, requests, header=FRAME_HEADER, meta_extra=None):
    name = f"{case}-{scheduler}-{budget}"
    d = os.path.join(out, name)
    os.makedirs(os.path.join(d, "frames"), exist_ok=True)
    with open(os.path.join(d, "run.json"), "w") as f:
        json.dump({"name": name, "case": case, "scheduler": scheduler, "budget_polygons": budget,
                   "mode": "live", "backbone_args": "--scheduler " + scheduler,
                   "frontend_args": "--deferred-reference", "wall_s": 1.0, "exit_code": 0,
                   **(meta_extra or {})}, f)
    with open(os.path.join(d, "frames.csv"), "w") as f:
        f.write(header + "\n" + "\n".join(rows) + "\n")
    with open(os.path.join(d, "decisions.csv"), "w") as f:
        f.write("frame,requests\n" + "".join(f"{i},{r}\n" for i, r in enumerate(requests)))
    with open(os.path.join(d, "frontend-summary.json"), "w") as f:
        json.dump({"reference_mode": "deferred", "frames_not_kept": 0}, f)
    shade = 60 if scheduler == "curves" else 160
    for frame in (0, 2):
        for kind, pixel in (("frame", lambda x, y: (shade, 2 * x, 2 * y, 255)),
                            ("reference", lambda x, y: (90, 2 * x, 2 * y, 255)),
                            ("difference", lambda x, y: (abs(shade - 90), 0, 0, 255))):
            with open(os.path.join(d, "frames", f"{kind}_{frame:04d}.png"), "wb") as f:
                f.write(png_bytes(64, 48, pixel))
    return name


def write_fixture(out):
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "settings.json"), "w") as f:
        json.dump({"mode": "live", "cases": ["room", "hall"], "schedulers": ["curves", "greedy"],
                   "command": "fixture", "runs": 4, "wall_s": 4.0}, f)
    # room / curves: blank first frame, complete from frame 1 (shown at 150 ms).
    write_run(out, "room", "curves", 200, [
        frame_row(0, 0.0, 0, 5000, "-inf", "", 40, 2, 2, 1),
        frame_row(1, 0.1, 150, 90000, "12.5", "30", 150, 2, 0, 0),
        frame_row(2, 0.2, 190, 20000, "inf", "35", 250, 2, 0, 0),
        frame_row(3, 1.1, 210, 1000, "8.0", "", 1150, 3, 1, 0)], [2, 1, 0, 0])
    # room / greedy: never complete; one frame unscored (empty SNR).
    write_run(out, "room", "greedy", 200, [
        frame_row(0, 0.0, 0, 5000, "-inf", "", 40, 2, 2, 1),
        frame_row(1, 0.1, 200, 60000, "14.0", "120", 150, 2, 1, 0),
        frame_row(2, 0.2, 200, 60000, "", "", 250, 2, 1, 0),
        frame_row(3, 1.1, 200, 1000, "9.0", "", 1150, 3, 1, 0)], [3, 3, 1, 0])
    for scheduler in ("curves", "greedy"):
        write_run(out, "hall", scheduler, 400, [
            frame_row(i, 0.1 * i, 300, 1000, f"{5 + i}", "50", 100 * i, 1, 0, 0)
            for i in range(3)], [1, 0, 0])
