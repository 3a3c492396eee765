#!/usr/bin/env python3
"""The workbench's results page (deploy/workbench_report.py, index.html) opened in headless
Chromium: the screenshot is not blank and the page logs nothing to the console (it reports
images that failed to decode there). Negative controls check that the two checks can fail: a
page that logs an error and has a broken image, and an empty page.
Exit 77 (ctest: skipped) when chromium is not installed."""
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest
import zlib

SOURCE = os.environ.get("THINLOD_SOURCE_DIR",
                        os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fixture import write_fixture  # noqa: E402

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def decode_png(data):
    """(width, height, rows of RGB(A) bytes) of an 8-bit RGB or RGBA PNG, filters 0-4."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and colour in (2, 6), f"PNG depth {depth} colour type {colour}"
            bpp = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw, stride, rows, prev = zlib.decompress(idat), width * bpp, [], bytearray(width * bpp)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, bpp, rows


def open_page(path, out_dir):
    """Screenshot path and console lines of `path` rendered by headless Chromium."""
    shot = os.path.join(out_dir, "shot.png")
    if os.path.exists(shot):
        os.remove(shot)
    done = subprocess.run(
        [CHROMIUM, "--headless=new", "--no-sandbox", "--disable-gpu", "--enable-logging=stderr",
         "--v=0", f"--user-data-dir={os.path.join(out_dir, 'profile')}", "--window-size=1200,1600",
         "--virtual-time-budget=5000", f"--screenshot={shot}", "file://" + os.path.abspath(path)],
        capture_output=True, text=True, timeout=90)
    console = [line for line in done.stderr.splitlines() if re.search(r":CONSOLE[:(]", line)]
    return shot, console, done


def non_background_fraction(shot):
    width, height, bpp, rows = decode_png(open(shot, "rb").read())
    background = rows[0][:3]
    differing = sum(1 for row in rows for x in range(width)
                    if row[x * bpp:x * bpp + 3] != background)
    return differing / (width * height)


class Page(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory()
        write_fixture(os.path.join(cls.dir.name, "results"))
        subprocess.run([sys.executable, os.path.join(SOURCE, "deploy", "workbench_report.py"),
                        os.path.join(cls.dir.name, "results")], check=True, capture_output=True)

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def test_the_results_page_renders_without_console_messages(self):
        shot, console, done = open_page(os.path.join(self.dir.name, "results", "index.html"),
                                        self.dir.name)
        self.assertTrue(os.path.exists(shot), done.stderr[-2000:])
        self.assertEqual(console, [])
        # Text, table borders and the inlined images: well above an empty page's 0.
        self.assertGreater(non_background_fraction(shot), 0.05)

    def test_negative_control_console_error_and_broken_image_are_caught(self):
        page = os.path.join(self.dir.name, "bad.html")
        with open(page, "w") as f:
            f.write("<!DOCTYPE html><html><body><h1>bad</h1>"
                    "<img alt=\"broken\" src=\"data:image/png;base64,AAAA\">"
                    + open(os.path.join(SOURCE, "deploy", "workbench_report.py")).read()
                    .split("IMAGE_CHECK = ")[1].split('"""')[1] +
                    "<script>console.error('boom')</script></body></html>")
        _, console, _ = open_page(page, self.dir.name)
        self.assertTrue(any("boom" in line for line in console), console)
        self.assertTrue(any("broken" in line for line in console), console)

    def test_negative_control_an_empty_page_is_blank(self):
        page = os.path.join(self.dir.name, "empty.html")
        with open(page, "w") as f:
            f.write("<!DOCTYPE html><html><body></body></html>")
        shot, console, _ = open_page(page, self.dir.name)
        self.assertEqual(console, [])
        self.assertEqual(non_background_fraction(shot), 0.0)


if __name__ == "__main__":
    if CHROMIUM is None:
        print("page_test: chromium not installed (deploy/setup installs it); skipped")
        sys.exit(77)
    unittest.main()
