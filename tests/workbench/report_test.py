#!/usr/bin/env python3
"""deploy/workbench_report.py: the metric functions and one report over a fixture folder."""
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

SOURCE = os.environ.get("THINLOD_SOURCE_DIR",
                        os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "deploy"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import workbench_report as report  # noqa: E402
from fixture import FRAME_HEADER, frame_row, write_fixture, write_run  # noqa: E402


def read(path):
    with open(path) as f:
        return f.read()


class Functions(unittest.TestCase):
    def test_nearest_rank_counts_infinities_and_drops_missing(self):
        values = [3.0, math.nan, -math.inf, 1.0, 2.0, math.inf]
        self.assertEqual(report.nearest_rank(values, 0.5), 2.0)  # of -inf 1 2 3 inf
        self.assertEqual(report.nearest_rank(values, 0.1), -math.inf)
        self.assertEqual(report.nearest_rank(values, 1.0), math.inf)
        self.assertIsNone(report.nearest_rank([math.nan], 0.5))

    def test_worst_window_is_the_largest_sum_over_one_second(self):
        times = [0.0, 0.5, 0.99, 1.0, 1.6, 3.0]
        amounts = [10, 20, 30, 40, 50, 5]
        # [0.5, 1.5): 20 + 30 + 40 = 90; [0.99, 1.99): 30 + 40 + 50 = 120.
        self.assertEqual(report.worst_window(times, amounts), 120)
        self.assertEqual(report.worst_window([0.0], [7]), 7)
        self.assertEqual(report.worst_window([], []), 0.0)

    def test_first_complete_needs_a_visible_object_and_none_missing(self):
        rows = [{"frame": "0", "visible_objects": "0", "missing_objects": "0", "shown_at_ms": "5"},
                {"frame": "1", "visible_objects": "2", "missing_objects": "1", "shown_at_ms": "9"},
                {"frame": "2", "visible_objects": "2", "missing_objects": "0", "shown_at_ms": "12"}]
        self.assertEqual(report.first_complete(rows), (2, 12.0))
        self.assertEqual(report.first_complete(rows[:2]), (None, None))
        # Unmeasured completeness (empty fields, e.g. --no-reference) is never complete.
        self.assertEqual(report.first_complete(
            [{"frame": "0", "visible_objects": "", "missing_objects": "", "shown_at_ms": ""}]),
            (None, None))

    def test_frame_units_prefer_the_units_column_then_the_triangles_of_a_frame_without_points(self):
        self.assertEqual(report.frame_units({"polygons": "150", "points": "30", "units": "170.00"}),
                         170.0)
        # frames.csv before the columns, and a frame without points: units are triangles.
        self.assertEqual(report.frame_units({"polygons": "150"}), 150.0)
        self.assertEqual(report.frame_units({"polygons": "150", "points": "0", "units": ""}), 150.0)
        # Points at an unknown kappa: unknown, never the triangles alone.
        self.assertTrue(math.isnan(report.frame_units({"polygons": "150", "points": "30",
                                                       "units": ""})))


def hybrid_row(frame, time_s, polygons, points, units):
    """A frame row with the newer columns: skinned_objects ... pose_bytes, points, units."""
    return frame_row(frame, time_s, polygons, 1000, "10", "", 100 * frame, 1, 0, 0) + \
        f",0,0,0,{points},{units}"


class HybridUnits(unittest.TestCase):
    """A run that drew points: the budget is checked in units, and --from-time drops a hold."""

    def report(self, *extra):
        d = tempfile.TemporaryDirectory()
        self.addCleanup(d.cleanup)
        with open(os.path.join(d.name, "settings.json"), "w") as f:
            json.dump({"mode": "live", "cases": ["field"], "schedulers": ["curves-hybrid"]}, f)
        write_run(d.name, "field", "curves-hybrid", 200, [
            hybrid_row(0, 0.0, 100, 0, "100.00"),
            hybrid_row(1, 1.0, 190, 30, "210.00"),   # 190 triangles, but 210 units: over
            hybrid_row(2, 2.0, 150, 60, ""),         # points at an unknown kappa
            hybrid_row(3, 3.0, 180, 15, "190.00")], [1, 0, 0, 0],
            header=FRAME_HEADER + ",skinned_objects,deformed_vertices,pose_bytes,points,units")
        done = subprocess.run([sys.executable, os.path.join(SOURCE, "deploy", "workbench_report.py"),
                               d.name] + list(extra), capture_output=True, text=True)
        self.assertEqual(done.returncode, 0, done.stderr)
        runs = json.loads(read(os.path.join(d.name, "table.json")))["runs"]
        self.assertEqual(len(runs), 1)
        return runs[0], read(os.path.join(d.name, "table.md"))

    def test_the_budget_is_checked_in_units(self):
        m, table = self.report()
        self.assertEqual(m["polygons_max"], 190)
        self.assertEqual(m["units_max"], 210.0)
        self.assertEqual(m["points_max"], 60)
        self.assertEqual(m["frames_over_budget"], 1)
        self.assertEqual(m["frames_units_unknown"], 1)
        self.assertIn("| units max | used % |", table)
        self.assertIn("| 190 | 210.0 | 83 |", table)
        # No complete frame in this fixture: the mean of every frame of known units,
        # (100 + 210 + 190) / 3 of 200.
        self.assertAlmostEqual(m["budget_used_pct"], 100.0 * 500.0 / 3.0 / 200.0)

    def test_budget_used_counts_from_the_first_complete_frame(self):
        rows = [{"frame": "0"}, {"frame": "1"}, {"frame": "2"}]
        self.assertAlmostEqual(report.budget_used_pct(rows, [10.0, 180.0, 200.0], 1, 200), 95.0)
        self.assertAlmostEqual(report.budget_used_pct(rows, [10.0, 180.0, 200.0], None, 200),
                               65.0)
        self.assertIsNone(report.budget_used_pct(rows, [10.0, 180.0, 200.0], 1, None))
        self.assertIsNone(report.budget_used_pct(rows, [math.nan] * 3, None, 200))

    def test_from_time_leaves_out_the_frames_before_it(self):
        m, _ = self.report("--from-time", "2")
        self.assertEqual(m["frames"], 2)
        self.assertEqual(m["from_time_s"], 2.0)
        self.assertEqual(m["frames_over_budget"], 0)
        self.assertEqual(m["units_max"], 190.0)
        self.assertEqual(m["polygons_max"], 180)


class CommandLine(unittest.TestCase):
    def test_help_prints_the_usage_and_succeeds(self):
        done = subprocess.run([sys.executable, os.path.join(SOURCE, "deploy", "workbench_report.py"),
                               "--help"], capture_output=True, text=True)
        self.assertEqual(done.returncode, 0, done.stderr)
        self.assertIn("Usage: deploy/workbench_report.py RESULTS_DIR", done.stdout)

    def test_a_missing_folder_is_a_usage_error(self):
        done = subprocess.run([sys.executable, os.path.join(SOURCE, "deploy", "workbench_report.py")],
                              capture_output=True, text=True)
        self.assertEqual(done.returncode, 2)
        self.assertIn("Usage:", done.stderr)


class OwnAnswer(unittest.TestCase):
    """frames.csv's own_answer column: the share of frames drawn with their own pose's answer,
    and the answer wait in the mode cell."""

    def test_share_of_frames_with_their_own_answer_and_the_wait_in_the_mode(self):
        d = tempfile.TemporaryDirectory()
        self.addCleanup(d.cleanup)
        with open(os.path.join(d.name, "settings.json"), "w") as f:
            json.dump({"mode": "live", "cases": ["field"], "schedulers": ["curves"]}, f)
        write_run(d.name, "field", "curves", 200, [
            hybrid_row(k, 0.1 * k, 100, 0, "100.00") + f",{int(k != 1)}" for k in range(4)],
            [0, 0, 0, 0],
            header=FRAME_HEADER + ",skinned_objects,deformed_vertices,pose_bytes,points,units,"
            "own_answer", meta_extra={"answer_wait_ms": 2})
        done = subprocess.run([sys.executable, os.path.join(SOURCE, "deploy", "workbench_report.py"),
                               d.name], capture_output=True, text=True)
        self.assertEqual(done.returncode, 0, done.stderr)
        m = json.loads(read(os.path.join(d.name, "table.json")))["runs"][0]
        self.assertEqual(m["own_answer_pct"], 75.0)
        self.assertEqual(m["mode"], "live +2 ms")
        self.assertIn("| own answer % |", read(os.path.join(d.name, "table.md")))

    def test_runs_before_the_column_have_no_share(self):
        m, _ = HybridUnits.report(self)
        self.assertIsNone(m["own_answer_pct"])
        self.assertEqual(m["mode"], "live")


class Report(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory()
        write_fixture(cls.dir.name)
        done = subprocess.run([sys.executable, os.path.join(SOURCE, "deploy", "workbench_report.py"),
                               cls.dir.name], capture_output=True, text=True)
        if done.returncode != 0:
            raise AssertionError(done.stderr)
        cls.table = json.loads(read(os.path.join(cls.dir.name, "table.json")))["runs"]
        cls.by_name = {m["name"]: m for m in cls.table}

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def test_one_row_per_run_in_suite_and_scheduler_order(self):
        self.assertEqual([m["name"] for m in self.table],
                         ["room-curves-200", "room-greedy-200", "hall-curves-400", "hall-greedy-400"])

    def test_metrics_of_a_run(self):
        m = self.by_name["room-curves-200"]
        self.assertEqual(m["frames"], 4)
        self.assertEqual(m["frames_scored"], 4)
        self.assertEqual(m["snr_db_median"], 8.0)    # of -inf 8 12.5 inf: element ceil(2) - 1
        self.assertEqual(m["snr_db_p10"], "-inf")
        self.assertEqual(m["snr_db_min"], "-inf")
        self.assertEqual(m["blank_frames"], 1)
        self.assertEqual(m["incomplete_frames"], 2)  # frames 0 and 3
        self.assertEqual(m["frames_over_budget"], 1)  # 210 > 200
        self.assertEqual(m["polygons_max"], 210)
        # frames.csv without points / units: units are the triangles.
        self.assertEqual(m["units_max"], 210.0)
        self.assertEqual(m["frames_units_unknown"], 0)
        self.assertAlmostEqual(m["link_kb_total"], 116.0)
        self.assertAlmostEqual(m["link_kb_worst_1s"], 115.0)  # frames 0-2 within 1 s
        self.assertEqual(m["simplifier_requests"], 3)
        self.assertEqual(m["update_latency_ms_median"], 30.0)
        self.assertEqual(m["first_complete_frame"], 1)
        self.assertEqual(m["first_complete_ms"], 150.0)
        self.assertEqual(m["reference_mode"], "deferred")

    def test_a_run_that_never_completes_and_an_unscored_frame(self):
        m = self.by_name["room-greedy-200"]
        self.assertIsNone(m["first_complete_ms"])
        self.assertEqual(m["frames_scored"], 3)
        self.assertEqual(m["frames_over_budget"], 0)
        self.assertEqual(m["simplifier_requests"], 7)

    def test_tables_agree_and_mark_the_best_median_per_case(self):
        with open(os.path.join(self.dir.name, "table.csv")) as f:
            rows = list(csv.DictReader(f))
        self.assertEqual([r["scheduler"] for r in rows], ["curves", "greedy", "curves", "greedy"])
        self.assertEqual(rows[1]["snr_db_median"], "9.0")
        md = read(os.path.join(self.dir.name, "table.md")).splitlines()
        self.assertEqual(len(md), 2 + 4)
        # room: greedy's median 9.0 beats curves' 8.0, and the table says so.
        self.assertIn("| **9.0** |", md[3])
        self.assertNotIn("**", md[2])
        self.assertIn("| - |", md[3])  # never complete

    def test_per_run_files_plot_and_page(self):
        for name in self.by_name:
            self.assertTrue(os.path.exists(os.path.join(self.dir.name, name, "metrics.json")))
            self.assertTrue(os.path.exists(os.path.join(self.dir.name, name, "metrics.csv")))
        page = read(os.path.join(self.dir.name, "index.html"))
        self.assertIn("data:image/png;base64,", page)
        self.assertNotIn('src="frames/', page)  # self-contained
        for case in ("room", "hall"):
            self.assertIn(f'<h2 id="{case}">', page)
        if report.shutil.which("gnuplot"):
            self.assertTrue(os.path.exists(os.path.join(self.dir.name, "snr-room.png")))


if __name__ == "__main__":
    unittest.main()
