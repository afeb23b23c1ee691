#!/usr/bin/env python3
"""e2e_toposlam_view_in_browser: `toposlam view` against the real toposlamd on the simulated office
(sim:office?route=loop2, 1618 frames, lossless queues), over real UDP multicast, its page driven in headless
Chromium through chromedriver (tests/apps/webdriver_check.py's WebDriver: W3C WebDriver over HTTP on
127.0.0.1, standard library only).

GIVEN `toposlam view` on a free port and its page open in Chromium before the daemon starts,
WHEN toposlamd runs the office route while this script also reads TOPOSLAM_TOPOLOGY itself, and a non-LCM
     datagram and an undecodable topology message arrive on the same group,
THEN, without a page reload,
  - the page's node count grew while the daemon ran (live updates), and at the end equals the last
    topology_t's num_nodes (> 0), with one node highlighted as current, one of the topology's nodes;
  - every node's thumbnail image decoded (naturalWidth > 0), and a revisit shows both its frames;
  - the status line says `finished`; the garbage is counted (1 garbage datagram, 1 undecodable topology)
    and the server still answers; a second `toposlam view` on the same port exits 1 naming the port;
    SIGTERM ends the view with exit status 0.
A screenshot of the final page is written to --screenshot.

Exit status: 0 ok, 1 an assertion failed (the message says which), 77 skipped (no Chromium or
chromedriver, no multicast).
Usage: live_view_check.py --toposlam T --toposlamd D --config YAML --work DIR --screenshot PNG
"""
import argparse
import json
import os
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "apps"))
import webdriver_check  # noqa: E402  (tests/apps: the WebDriver client of the report's browser test)
from webdriver_check import WebDriver, free_port  # noqa: E402

import toposlam_lcm  # noqa: E402
from toposlam_lcm.udpm_reader import UdpmReader, parse_url  # noqa: E402

URL = "udpm://239.255.76.67:7667?ttl=0"  # inside the test's own network namespace (in_netns.sh)

PAGE_STATE = """
var s = document.getElementById('view-state').dataset;
var imgs = Array.prototype.slice.call(document.querySelectorAll('#graph .node img'));
var revisitImgs = Array.prototype.slice.call(document.querySelectorAll('#revisits img'));
return {
  updates: +s.updates, nodes: +s.nodes, current: +s.current, revision: +s.revision,
  current_elements: document.querySelectorAll('#graph .node.current').length,
  node_ids: Array.prototype.map.call(document.querySelectorAll('#graph .node'), function (e) { return +e.dataset.node; }),
  thumbnails_loaded: imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length,
  thumbnails: imgs.length,
  revisit_rows: document.querySelectorAll('#revisits .revisit').length,
  revisit_images_loaded: revisitImgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length,
  status: document.getElementById('status').textContent,
  footer: document.getElementById('lcm').textContent,
  not_reloaded: window.__liveViewTestMark === 1
};
"""


def fail(message):
    print("FAIL: " + message, flush=True)
    sys.exit(1)


def skip(message):
    print("SKIP: " + message, flush=True)
    sys.exit(77)


def probe_multicast():
    group, port, _ = parse_url(URL)
    try:
        with UdpmReader(URL, channels=["TOPOSLAM_E2E_PROBE"]) as reader:
            send_datagram(struct.pack(">II", 0x4C433032, 0) + b"TOPOSLAM_E2E_PROBE\0x")
            if reader.read(timeout=3) == ("TOPOSLAM_E2E_PROBE", b"x"):
                return
    except OSError as e:
        skip("multicast unavailable: %s" % e)
    skip("a datagram sent to %s:%d did not come back (no multicast route?)" % (group, port))


def send_datagram(data):
    group, port, _ = parse_url(URL)
    out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    out.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
    out.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
    out.sendto(data, (group, port))
    out.close()


class TopologyCollector(threading.Thread):
    """Reads TOPOSLAM_TOPOLOGY itself: the last topology_t toposlamd published, to compare the page with."""

    def __init__(self):
        super().__init__(daemon=True)
        self.reader = UdpmReader(URL, channels=["TOPOSLAM_TOPOLOGY"])
        self.last = None
        self.count = 0
        self.stop = threading.Event()

    def run(self):
        while not self.stop.is_set():
            message = self.reader.read(timeout=0.3)
            if message is None:
                continue
            try:
                self.last = toposlam_lcm.topology_t.decode(message[1])
                self.count += 1
            except Exception:
                pass  # the test's own garbage message


def get_json(url):
    with urllib.request.urlopen(url, timeout=5) as response:
        return json.loads(response.read().decode())


def main():
    parser = argparse.ArgumentParser()
    for option in ("--toposlam", "--toposlamd", "--config", "--work", "--screenshot"):
        parser.add_argument(option, required=True)
    args = parser.parse_args()
    browser = next((shutil.which(b) for b in ("chromium", "chromium-browser", "google-chrome") if shutil.which(b)), None)
    chromedriver = shutil.which("chromedriver")
    if not browser or not chromedriver:
        skip("needs chromium and chromedriver (Debian packages chromium, chromium-driver; scripts/setup.sh --test)")
    if not os.environ.get("TOPOSLAM_IN_NETNS"):
        skip("no network namespace here (unshare -rn failed): the counts need a private multicast group")
    probe_multicast()
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)

    port = free_port()
    base = "http://127.0.0.1:%d" % port
    view_log = open(os.path.join(args.work, "view.log"), "w")
    view = subprocess.Popen([args.toposlam, "view", "-c", args.config, "--lcm-url", URL, "--port", str(port)],
                            stdout=view_log, stderr=subprocess.STDOUT)
    processes = [view]
    profile = tempfile.mkdtemp(prefix="toposlam-view-webdriver-")
    driver_port = free_port()
    driver_log = open(os.path.join(args.work, "chromedriver.log"), "w")
    try:
        deadline = time.monotonic() + 20
        while True:
            try:
                get_json(base + "/state")
                break
            except OSError:
                if view.poll() is not None or time.monotonic() > deadline:
                    fail("toposlam view did not answer on %s (exit %s): %s" %
                         (base, view.poll(), open(view_log.name).read()))
                time.sleep(0.1)

        # A second view on the same port: exit status 1, the port named.
        second = subprocess.run([args.toposlam, "view", "--lcm-url", URL, "--port", str(port)],
                                capture_output=True, text=True, timeout=30)
        if second.returncode != 1 or ("port %d" % port) not in second.stderr:
            fail("a second view on port %d: exit %d, stderr %r" % (port, second.returncode, second.stderr))
        print("second view on the busy port: exit 1, %s" % second.stderr.strip(), flush=True)

        chromedriver_process = subprocess.Popen([chromedriver, "--port=%d" % driver_port, "--allowed-ips=127.0.0.1"],
                                                stdout=driver_log, stderr=subprocess.STDOUT)
        processes.append(chromedriver_process)
        driver = WebDriver(driver_port)
        driver.wait_ready(20)
        driver.start(browser, profile)
        driver.call("POST", driver.s("/url"), {"url": base + "/"})
        driver.run("window.__liveViewTestMark = 1; return 0;")
        deadline = time.monotonic() + 20
        while driver.run(PAGE_STATE)["updates"] < 1:
            if time.monotonic() > deadline:
                fail("the page received no event from /events within 20 s")
            time.sleep(0.1)

        collector = TopologyCollector()
        collector.start()
        send_datagram(b"not an LCM datagram")
        send_datagram(struct.pack(">II", 0x4C433032, 1) + b"TOPOSLAM_TOPOLOGY\0" + b"\x01garbage, not a topology_t")

        daemon_log = open(os.path.join(args.work, "toposlamd.log"), "w")
        daemon = subprocess.Popen([args.toposlamd, "-c", args.config, "--source", "sim:office?route=loop2",
                                   "--map", os.path.join(args.work, "office.tsm"), "--no-map-load",
                                   "--overflow", "block", "--lcm-url", URL], stdout=daemon_log,
                                  stderr=subprocess.STDOUT)
        processes.append(daemon)
        node_counts_seen = set()
        while daemon.poll() is None:
            node_counts_seen.add(driver.run(PAGE_STATE)["nodes"])
            time.sleep(0.25)
        if daemon.returncode != 0:
            fail("toposlamd exited with %d: %s" % (daemon.returncode, open(daemon_log.name).read()[-2000:]))

        # The daemon has finished: wait for the page to show its last topology.
        time.sleep(0.5)
        collector.stop.set()
        collector.join(2)
        last = collector.last
        if last is None:
            fail("no topology_t received from toposlamd")
        deadline = time.monotonic() + 15
        while True:
            page = driver.run(PAGE_STATE)
            settled = page["revision"] == last.map_revision and "finished" in page["status"] and \
                page["thumbnails_loaded"] == page["thumbnails"]
            if settled or time.monotonic() > deadline:
                break
            time.sleep(0.2)
        state = get_json(base + "/state")
        driver.call("POST", driver.s("/window/rect"), {"width": 1400, "height": 1000})
        png = webdriver_check.base64.b64decode(driver.call("GET", driver.s("/screenshot")))
        with open(args.screenshot, "wb") as f:
            f.write(png)
        driver.call("DELETE", driver.s(""))

        topology_ids = sorted(n.id for n in last.nodes)
        print("toposlamd: %d topology messages, the last: revision %d, %d nodes, %d edges, current node %d"
              % (collector.count, last.map_revision, last.num_nodes, last.num_edges, last.current_node))
        print("page: %d updates, node counts seen while running %s, at the end %d nodes, revision %d, current "
              "node %d (%d highlighted), %d/%d thumbnails decoded, %d revisits (%d images decoded)"
              % (page["updates"], sorted(node_counts_seen), page["nodes"], page["revision"], page["current"],
                 page["current_elements"], page["thumbnails_loaded"], page["thumbnails"], page["revisit_rows"],
                 page["revisit_images_loaded"]))
        print("page status: " + page["status"])
        print("page footer: " + page["footer"])
        print("screenshot: %s (%d bytes)" % (args.screenshot, len(png)), flush=True)

        if not page["not_reloaded"]:
            fail("the page was reloaded (its window mark is gone)")
        if len([n for n in node_counts_seen if n > 0]) < 2:
            fail("the node count did not change while toposlamd ran (seen %s): no live updates" % sorted(node_counts_seen))
        if not last.num_nodes > 0 or page["nodes"] != last.num_nodes:
            fail("the page shows %d nodes, the last topology_t has %d" % (page["nodes"], last.num_nodes))
        if sorted(page["node_ids"]) != topology_ids:
            fail("the page's node ids %s are not the topology's %s" % (sorted(page["node_ids"]), topology_ids))
        if page["current_elements"] != 1 or page["current"] not in topology_ids:
            fail("%d nodes highlighted as current (node %d)" % (page["current_elements"], page["current"]))
        if page["current"] != state["current_node"]:
            fail("the page highlights node %d, the server says %d" % (page["current"], state["current_node"]))
        if page["thumbnails_loaded"] < 1 or page["thumbnails_loaded"] != page["nodes"]:
            fail("%d of %d nodes' thumbnails decoded" % (page["thumbnails_loaded"], page["nodes"]))
        if page["revisit_rows"] < 1 or page["revisit_images_loaded"] != 2 * page["revisit_rows"]:
            fail("%d revisits shown with %d images decoded" % (page["revisit_rows"], page["revisit_images_loaded"]))
        if "finished" not in page["status"] or "camera " not in page["status"]:
            fail("the status line says %r" % page["status"])
        if state["reader"].get("garbage") != 1 or state["undecodable"]["topology"] != 1:
            fail("garbage counted: %d datagrams, %d undecodable topology messages (1 and 1 sent)"
                 % (state["reader"].get("garbage", 0), state["undecodable"]["topology"]))
        if "1 undecodable" not in page["footer"] or "1 garbage datagrams" not in page["footer"]:
            fail("the page's footer does not count the garbage: %r" % page["footer"])
        if len(png) < 20000 or png[:8] != b"\x89PNG\r\n\x1a\n":
            fail("screenshot missing or nearly blank (%d bytes)" % len(png))

        view.terminate()
        status = view.wait(10)
        if status != 0:
            fail("toposlam view exited with %d after SIGTERM" % status)
        print("live view OK", flush=True)
        return 0
    finally:
        for process in reversed(processes):
            if process.poll() is None:
                process.terminate()
                try:
                    process.wait(10)
                except subprocess.TimeoutExpired:
                    process.kill()
        shutil.rmtree(profile, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
