#!/usr/bin/env python3
"""deploy/aslod-aerobic.py (docs/results/aslod.md): its per-run numbers on a hand-made run folder
of four frames whose every value is known."""
import importlib.util
import math
import os
import sys
import tempfile
import unittest

SOURCE = os.environ.get("THINLOD_SOURCE_DIR",
                        os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "deploy"))
_spec = importlib.util.spec_from_file_location(
    "aslod_aerobic", os.path.join(SOURCE, "deploy", "aslod-aerobic.py"))
aerobic = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(aerobic)

FRAMES = ("frame,time_s,polygons,link_bytes,render_ms,update_latency_ms,uploaded_bytes,"
          "skinned_objects,deformed_vertices,pose_bytes,snr_db\n")
OBJECTS = "frame,time_s,object,kind,triangles,vertices,skinned,posed,x,y,z\n"


def write_run(root, frames, objects, budget=5000):
    run = os.path.join(root, f"aerobic-class-curves-{budget}")
    os.makedirs(run)
    with open(os.path.join(run, "frames.csv"), "w") as f:
        f.write(FRAMES + "".join(",".join(str(v) for v in row) + "\n" for row in frames))
    with open(os.path.join(run, "objects.csv"), "w") as f:
        f.write(OBJECTS + "".join(",".join(str(v) for v in row) + "\n" for row in objects))
    return run


# Frame 0: nothing held. Frames 1-3: the left figure (x -3) posed, 100 triangles / 80 vertices;
# the right one (x 3) held but without a pose in frame 1 (not drawn), posed from frame 2 with
# 300 / 200 (frame 3: 5,100 triangles, over the budget). Frame 2 receives no pose and draws
# an older one (no update visible); frame 3 shows its own pose's update 5 ms after sending.
FRAMES_ROWS = [
    (0, 0.0, 0, 0, 2.0, "", 0, 0, 0, 0, "-inf"),
    (1, 0.1, 100, 6000, 4.0, 5.0, 9000, 1, 80, 1776, 10.0),
    (2, 0.2, 400, 0, 4.0, "", 0, 2, 280, 0, 8.0),
    (3, 0.3, 5100, 5504, 6.0, 5.0, 0, 2, 280, 3552, 20.0),
]
OBJECT_ROWS = [
    (1, 0.1, 1, "Mesh", 100, 80, 1, 1, -3, 0, 0), (1, 0.1, 3, "Mesh", 300, 200, 1, 0, 3, 0, 0),
    (2, 0.2, 1, "Mesh", 100, 80, 1, 1, -3, 0, 0), (2, 0.2, 3, "Mesh", 300, 200, 1, 1, 3, 0, 0),
    (3, 0.3, 1, "Mesh", 100, 80, 1, 1, -3, 0, 0), (3, 0.3, 3, "Mesh", 5000, 200, 1, 1, 3, 0, 0),
]


class AerobicNumbers(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.run = write_run(self.tmp.name, FRAMES_ROWS, OBJECT_ROWS)
        self.stats = aerobic.run_stats(self.run)

    def tearDown(self):
        self.tmp.cleanup()

    def test_cv_is_the_population_deviation_over_the_mean(self):
        mean, sd, cv = aerobic.cv_stats([2.0, 4.0, 4.0, 6.0])
        self.assertEqual(mean, 4.0)
        self.assertAlmostEqual(sd, math.sqrt(2.0))
        self.assertAlmostEqual(cv, math.sqrt(2.0) / 4.0)
        self.assertTrue(math.isnan(aerobic.cv_stats([3.0])[2]))

    def test_an_unposed_skinned_object_is_not_counted_as_drawn(self):
        objects = self.stats["objects"]
        self.assertEqual(objects[1], {"left (Run)": 100})
        self.assertEqual(objects[2], {"left (Run)": 100, "right (Run)": 300})

    def test_triangles_budget_and_vertex_check(self):
        st = self.stats
        self.assertEqual((st["tris_min"], st["tris_max"], st["over_budget"]), (0, 5100, 1))
        self.assertEqual(st["budget"], 5000)
        self.assertEqual(st["vertex_mismatch_frames"], 0)
        self.assertEqual(st["full_vertices"], 3 * 3205)

    def test_a_frame_whose_vertices_disagree_with_the_objects_is_counted(self):
        rows = [list(r) for r in FRAMES_ROWS]
        rows[3][8] = 281
        with tempfile.TemporaryDirectory() as tmp:
            st = aerobic.run_stats(write_run(tmp, rows, OBJECT_ROWS))
        self.assertEqual(st["vertex_mismatch_frames"], 1)

    def test_pose_bytes_and_their_share_of_the_link(self):
        st = self.stats
        self.assertEqual(st["pose_total"], 1776 + 3552)
        self.assertEqual(st["link_total"], 6000 + 5504)
        self.assertEqual(st["frames_without_pose"], 2)  # frames 0 and 2

    def test_frames_from_3_on_are_split_by_whether_they_show_their_own_pose(self):
        st = self.stats
        self.assertEqual(st["frames_older_pose"], 0)  # frame 3 shows its own
        self.assertEqual(st["snr_med_fresh"], 20.0)
        rows = [list(r) for r in FRAMES_ROWS]
        rows[3][5] = 105.0  # a slot late: an older pose
        with tempfile.TemporaryDirectory() as tmp:
            st = aerobic.run_stats(write_run(tmp, rows, OBJECT_ROWS))
        self.assertEqual(st["frames_older_pose"], 1)
        self.assertEqual(st["snr_med_stale"], 20.0)

    def test_shares_per_window_sum_to_one(self):
        (lo, hi, per), *rest = aerobic.shares(self.stats)
        self.assertEqual((lo, hi), (0.0, 3.0))
        self.assertAlmostEqual(sum(share for _, share in per.values()), 1.0)
        # Three frames hold something: left 100 each, right 300 and 5,000 in two of them.
        self.assertAlmostEqual(per["left (Run)"][0], 100.0)
        self.assertAlmostEqual(per["right (Run)"][0], 5300.0 / 3)
        self.assertEqual([p for _, _, p in rest], [{}, {}, {}])


if __name__ == "__main__":
    unittest.main()
