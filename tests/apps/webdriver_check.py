#!/usr/bin/env python3
"""Opens a `toposlam report` page in headless Chromium through chromedriver (W3C WebDriver over HTTP on
127.0.0.1, Python standard library only), reads what the real browser rendered and takes a full-page
screenshot. Fails (exit 1) when
  - an <img> did not decode (naturalWidth 0) or there are fewer <img> / <figure> / <svg> than expected,
  - the page shows a thumbnail placeholder ("no frame"),
  - the page's own check (#image-check) does not say `images-ok N`,
  - the rooms strip is expected but missing, or the screenshot is missing or blank.
The expected counts come from the run folder, mirroring src/eval/report.cpp: one <figure> per thumbnail
of the grid (every ceil(n/96)-th frame), one <img> per grid thumbnail plus one per topology node, and one
<svg> per figure the run and its eval.json allow.

Usage: webdriver_check.py --chromedriver PATH --browser PATH --page report.html --run RUN_DIR
                          --screenshot out.png [--expect-rooms]
"""
import argparse
import base64
import csv
import json
import math
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class WebDriver:
    """The few W3C WebDriver commands this check needs."""

    def __init__(self, port):
        self.base = "http://127.0.0.1:%d" % port
        self.session = None

    def call(self, method, path, body=None, timeout=60):
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(self.base + path, data=data, method=method,
                                         headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(request, timeout=timeout) as response:
                return json.loads(response.read().decode())["value"]
        except urllib.error.HTTPError as e:
            fail("WebDriver %s %s: HTTP %d %s" % (method, path, e.code, e.read().decode()[:500]))

    def wait_ready(self, seconds):
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            try:
                with urllib.request.urlopen(self.base + "/status", timeout=2) as response:
                    if json.loads(response.read().decode())["value"].get("ready"):
                        return
            except (urllib.error.URLError, ConnectionError, OSError):
                pass
            time.sleep(0.1)
        fail("chromedriver did not become ready within %d s" % seconds)

    def start(self, browser, profile):
        options = {"binary": browser,
                   "args": ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                            "--no-first-run", "--disable-background-networking", "--disable-component-update",
                            "--disable-sync", "--hide-scrollbars", "--window-size=1400,1000",
                            "--user-data-dir=" + profile]}
        value = self.call("POST", "/session", {"capabilities": {"alwaysMatch": {
            "browserName": "chrome", "goog:chromeOptions": options}}})
        self.session = value["sessionId"]

    def run(self, script):
        return self.call("POST", "/session/%s/execute/sync" % self.session, {"script": script, "args": []})

    def s(self, path):
        return "/session/%s%s" % (self.session, path)


PAGE_FACTS = """
var images = Array.prototype.slice.call(document.images);
return {
  ready: document.readyState,
  images: images.map(function (i) {
    return {alt: i.alt, complete: i.complete, naturalWidth: i.naturalWidth, naturalHeight: i.naturalHeight};
  }),
  figures: document.querySelectorAll('figure').length,
  svgs: document.querySelectorAll('svg').length,
  placeholders: document.querySelectorAll('.nothumb').length,
  marker: (document.getElementById('image-check') || {}).textContent || '',
  rooms_strip: document.body.innerHTML.indexOf('true room') >= 0,
  width: document.documentElement.scrollWidth,
  height: document.documentElement.scrollHeight
};
"""


def expected_counts(run_dir):
    """What src/eval/report.cpp draws for this run folder."""
    with open(os.path.join(run_dir, "frames.csv")) as f:
        frames = sum(1 for _ in csv.DictReader(f))
    step = max(1, math.ceil(frames / 96))
    grid = math.ceil(frames / step)
    nodes, history = 0, 0
    topology = os.path.join(run_dir, "topology.json")
    if os.path.exists(topology):
        with open(topology) as f:
            t = json.load(f)
        nodes, history = len(t.get("nodes", [])), len(t.get("history", []))
    timing = 0
    if os.path.exists(os.path.join(run_dir, "timing.csv")):
        with open(os.path.join(run_dir, "timing.csv")) as f:
            timing = sum(1 for _ in csv.DictReader(f))
    pr_points = 0
    if os.path.exists(os.path.join(run_dir, "eval.json")):
        with open(os.path.join(run_dir, "eval.json")) as f:
            pr_points = len(json.load(f).get("loop_closure", {}).get("curve", []))
    # strip + lambda2, the topology drawing, probability, timing, precision-recall (rooms strip added by caller)
    svgs = 2 + (1 if nodes else 0) + (1 if history else 0) + (1 if timing else 0) + (1 if pr_points else 0)
    return {"frames": frames, "grid": grid, "images": grid + nodes, "svgs": svgs}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--chromedriver", required=True)
    parser.add_argument("--browser", required=True)
    parser.add_argument("--page", required=True)
    parser.add_argument("--run", required=True)
    parser.add_argument("--screenshot", required=True)
    parser.add_argument("--expect-rooms", action="store_true")
    args = parser.parse_args()

    expected = expected_counts(args.run)
    if args.expect_rooms:
        expected["svgs"] += 1
    port = free_port()
    profile = tempfile.mkdtemp(prefix="toposlam-webdriver-")
    log = open(args.screenshot + ".chromedriver.log", "w")
    driver_process = subprocess.Popen([args.chromedriver, "--port=%d" % port, "--allowed-ips=127.0.0.1"],
                                      stdout=log, stderr=subprocess.STDOUT)
    driver = WebDriver(port)
    try:
        driver.wait_ready(20)
        driver.start(args.browser, profile)
        driver.call("POST", driver.s("/url"), {"url": "file://" + os.path.abspath(args.page)})
        # Wait for the load event and for every image to finish decoding (complete), at most 30 s.
        deadline = time.monotonic() + 30
        while True:
            facts = driver.run(PAGE_FACTS)
            settled = facts["ready"] == "complete" and all(i["complete"] for i in facts["images"]) and \
                facts["marker"] != "images-pending"
            if settled or time.monotonic() > deadline:
                break
            time.sleep(0.2)

        # Full-page screenshot: grow the window until its viewport holds the whole page (the outer window
        # includes some browser chrome; headless windows may exceed the screen).
        page_height = min(int(facts["height"]), 16000)
        driver.call("POST", driver.s("/window/rect"), {"width": 1400, "height": page_height + 200})
        viewport = driver.run("return window.innerHeight;")
        if viewport < page_height:
            print("note: viewport %d px shorter than the page (%d px): the screenshot shows the top" %
                  (viewport, page_height))
        png = base64.b64decode(driver.call("GET", driver.s("/screenshot")))
        with open(args.screenshot, "wb") as f:
            f.write(png)
        driver.call("DELETE", driver.s(""))
    finally:
        driver_process.terminate()
        try:
            driver_process.wait(10)
        except subprocess.TimeoutExpired:
            driver_process.kill()
        log.close()
        shutil.rmtree(profile, ignore_errors=True)

    broken = [i for i in facts["images"] if not (i["complete"] and i["naturalWidth"] > 0)]
    print("browser: %d <img> (expected %d: %d grid thumbnails + topology nodes), %d <figure> (expected %d), "
          "%d <svg> (expected >= %d), %d placeholders, marker '%s', page %dx%d, screenshot %d bytes"
          % (len(facts["images"]), expected["images"], expected["grid"], facts["figures"], expected["grid"],
             facts["svgs"], expected["svgs"], facts["placeholders"], facts["marker"], facts["width"],
             facts["height"], len(png)))
    if broken:
        fail("%d image(s) with naturalWidth 0 or not loaded: %s" % (len(broken), [i["alt"] for i in broken][:10]))
    if facts["placeholders"]:
        fail("%d thumbnail placeholder(s) ('no frame') on the page" % facts["placeholders"])
    if len(facts["images"]) < expected["images"]:
        fail("fewer <img> than expected")
    if facts["figures"] < expected["grid"]:
        fail("fewer thumbnail <figure>s than expected")
    if facts["svgs"] < expected["svgs"]:
        fail("fewer <svg> figures than expected")
    if facts["marker"] != "images-ok %d" % len(facts["images"]):
        fail("the page's own image check says '%s'" % facts["marker"])
    if args.expect_rooms and not facts["rooms_strip"]:
        fail("the ground-truth rooms strip is missing")
    if len(png) < 50000 or png[:8] != b"\x89PNG\r\n\x1a\n":
        fail("screenshot missing or nearly blank (%d bytes)" % len(png))
    print("PASS " + args.page)


if __name__ == "__main__":
    main()
