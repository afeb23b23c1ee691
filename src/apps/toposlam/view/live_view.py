"""toposlam's live view: a small web server that shows what toposlamd publishes over LCM, as it happens.

`toposlam view` runs this file (with python3; the standard library and the package toposlam_lcm only).
One thread reads the daemon's channels with toposlam_lcm.udpm_reader (place estimates, place events with
their JPEG thumbnails, the topology, the status) into a LiveViewState; the HTTP server
(http.server.ThreadingHTTPServer) serves

  /                       the page (live_view.html beside this file: its own JS and CSS, nothing fetched
                          from elsewhere)
  /state                  the state as one JSON object
  /events                 the same object as Server-Sent Events, each time it changes (at most 5 per second)
  /thumbnail/PLACE.jpg    a place's thumbnail as toposlamd sent it

Bad input from the network (datagrams that are not LCM, messages that do not decode as the channel's
type, e.g. from a daemon built with other message definitions) is counted, shown on the page and skipped.
Thread-safety: LiveViewState is shared by the reader thread and the HTTP threads under its own lock.

Exit status, as every toposlam command: 0 stopped by SIGINT or SIGTERM, 1 runtime error (the port is in
use, the page cannot be read), 2 usage error (a bad option or address).
"""

import argparse
import collections
import errno
import json
import math
import os
import signal
import socket
import sys
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import toposlam_lcm
from toposlam_lcm.udpm_reader import DEFAULT_URL, UdpmReader, parse_url

PROGRAM = "toposlam view"
EVENTS_MIN_INTERVAL_S = 0.2  # at most 5 updates per second per page: place_t arrives with every frame
EVENTS_KEEPALIVE_S = 15.0  # an SSE comment when nothing changed, so proxies and browsers keep the stream
REVISITS_SHOWN = 6
THUMBNAIL_BYTES_KEPT = 64 << 20  # about 20,000 places of toposlamd's 1.4-3.4 kB thumbnails


def finite(x):
    """x, or None when it is NaN or infinite (JSON has neither; the page shows "-")."""
    return x if math.isfinite(x) else None


class LiveViewState:
    """What the page shows, built from decoded LCM messages. No sockets: tests feed it payloads.

    accept(kind, payload) takes one message of a channel kind (place, place_event, topology, status);
    a payload that does not decode is counted in `undecodable` and changes nothing else.
    """

    KINDS = ("place", "place_event", "topology", "status")
    _TYPES = {"place": "place_t", "place_event": "place_event_t", "topology": "topology_t", "status": "status_t"}

    def __init__(self, thumbnail_bytes_kept=THUMBNAIL_BYTES_KEPT):
        self._lock = threading.Condition()
        self.version = 0
        self.messages = dict.fromkeys(self.KINDS, 0)
        self.undecodable = dict.fromkeys(self.KINDS, 0)
        self.last_error = ""
        self.reader_stats = {}
        self.network = "starting"
        self._topology = None
        self._place = None
        self._status = None
        self._events = {}  # place -> its place event (without the JPEG)
        self._thumbnails = collections.OrderedDict()  # place -> JPEG bytes, oldest first
        self._thumbnail_bytes = 0
        self._thumbnail_bytes_kept = thumbnail_bytes_kept
        self.thumbnails_dropped = 0
        self._revisits = collections.deque(maxlen=REVISITS_SHOWN)

    # --- input (the reader thread)

    def accept(self, kind, payload):
        try:
            message = getattr(toposlam_lcm, self._TYPES[kind]).decode(payload)
        except Exception as e:  # a wrong fingerprint (ValueError), a short buffer (struct.error), ...
            with self._lock:
                self.undecodable[kind] += 1
                self.last_error = "%s: %s" % (kind, e)
                self._changed()
            return False
        with self._lock:
            self.messages[kind] += 1
            getattr(self, "_on_" + kind)(message)
            self._changed()
        return True

    def set_network(self, text, reader_stats=None):
        with self._lock:
            if text != self.network or (reader_stats is not None and reader_stats != self.reader_stats):
                self.network = text
                if reader_stats is not None:
                    self.reader_stats = dict(reader_stats)
                self._changed()

    def _changed(self):
        self.version += 1
        self._lock.notify_all()

    def _on_place(self, p):
        self._place = {"frame": p.frame, "place": p.place, "node": p.node, "probability": finite(p.probability),
                       "latency_ms": finite(p.latency_ms), "match_frame": p.match_frame, "match_place": p.match_place,
                       "match_node": p.match_node, "map_revision": p.map_revision}

    def _on_place_event(self, e):
        event = {"place": e.place, "node": e.node, "is_new": bool(e.is_new), "probability": finite(e.probability),
                 "first_frame": e.first_frame, "last_frame": e.last_frame,
                 "representative_frame": e.representative_frame, "map_revision": e.map_revision,
                 "thumbnail": e.jpeg_size > 0}
        self._events[e.place] = event
        if e.jpeg_size > 0:
            self._keep_thumbnail(e.place, bytes(e.jpeg))
        if not e.is_new:
            self._revisits.appendleft(event)

    def _keep_thumbnail(self, place, jpeg):
        old = self._thumbnails.pop(place, None)
        if old is not None:
            self._thumbnail_bytes -= len(old)
        self._thumbnails[place] = jpeg
        self._thumbnail_bytes += len(jpeg)
        while self._thumbnail_bytes > self._thumbnail_bytes_kept and len(self._thumbnails) > 1:
            _, dropped = self._thumbnails.popitem(last=False)
            self._thumbnail_bytes -= len(dropped)
            self.thumbnails_dropped += 1

    def _on_topology(self, t):
        self._topology = {
            "map_revision": t.map_revision, "probability": finite(t.probability), "particles": t.particles,
            "current_node": t.current_node,
            "nodes": [{"id": n.id, "places": list(n.places), "representative_frames": list(n.representative_frames)}
                      for n in t.nodes],
            "edges": [{"from": e.from_node, "to": e.to_node, "count": e.count} for e in t.edges]}

    def _on_status(self, s):
        self._status = {
            "state": s.state, "uptime_s": finite(s.uptime_s), "fps": finite(s.fps),
            "frames_captured": s.frames_captured,
            "frames_published": s.frames_published, "frames_dropped": s.frames_dropped,
            "source_skipped": s.source_skipped, "source_state": s.source_state,
            "source_reconnects": s.source_reconnects, "source_dropped": s.source_dropped,
            "latency_median_ms": finite(s.latency_median_ms), "latency_p99_ms": finite(s.latency_p99_ms),
            "cpu_percent": finite(s.cpu_percent), "places": s.places, "map_revision": s.map_revision,
            "motion_state": s.motion_state}

    # --- output (the HTTP threads)

    def thumbnail(self, place):
        with self._lock:
            return self._thumbnails.get(place)

    def wait_for_change(self, seen_version, timeout):
        """Blocks until the version differs from seen_version or timeout seconds passed; returns the version."""
        with self._lock:
            self._lock.wait_for(lambda: self.version != seen_version, timeout)
            return self.version

    def snapshot(self):
        """The state as the page reads it (JSON-ready)."""
        with self._lock:
            nodes, edges, current, current_kind = [], [], -1, "none"
            topology = self._topology
            if topology is not None:
                for n in topology["nodes"]:
                    nodes.append({"id": n["id"], "places": n["places"], "thumbnail": self._thumbnail_of(n["places"])})
                edges = topology["edges"]
                current, current_kind = topology["current_node"], "last place"
            place = self._place
            if place is not None and place["match_node"] >= 0:
                current, current_kind = place["match_node"], "back at"
            elif place is not None and place["node"] >= 0:
                current, current_kind = place["node"], "last place"
            node_places = {n["id"]: n["places"] for n in nodes}
            revisits = []
            for event in self._revisits:
                matched = [q for q in node_places.get(event["node"], []) if q != event["place"]]
                revisit = dict(event)
                revisit["matched_place"] = self._thumbnail_of(matched)
                revisit["thumbnail"] = event["place"] if event["place"] in self._thumbnails else None
                revisits.append(revisit)
            return {
                "version": self.version,
                "map_revision": topology["map_revision"] if topology else -1,
                "topology_probability": topology["probability"] if topology else None,
                "particles": topology["particles"] if topology else 0,
                "nodes": nodes, "edges": edges,
                "current_node": current, "current_kind": current_kind,
                "place": place, "status": self._status, "revisits": revisits,
                "places_seen": len(self._events),
                "messages": dict(self.messages), "undecodable": dict(self.undecodable),
                "last_error": self.last_error, "network": self.network, "reader": dict(self.reader_stats),
                "thumbnails_dropped": self.thumbnails_dropped}

    def _thumbnail_of(self, places):
        """The earliest of places with a thumbnail kept, or None."""
        for q in sorted(places):
            if q in self._thumbnails:
                return q
        return None


def read_lcm(state, url, channels, stop, retry_s=2.0):
    """The reader thread: (channel, payload) pairs into state until stop is set. channels: name -> kind.
    Joining the group fails while the host has no multicast route; it is tried again every retry_s."""
    group, port, _ = parse_url(url)
    while not stop.is_set():
        try:
            reader = UdpmReader(url, channels=list(channels))
        except OSError as e:
            state.set_network("cannot join %s:%d (%s); trying again every %g s" % (group, port, e.strerror, retry_s))
            stop.wait(retry_s)
            continue
        with reader:
            state.set_network("listening on %s" % url, reader.stats)
            while not stop.is_set():
                try:
                    message = reader.read(timeout=0.5)
                except OSError as e:
                    state.set_network("receive failed on %s (%s); joining again" % (url, e.strerror))
                    break
                if message is not None:
                    state.accept(channels[message[0]], message[1])
                state.set_network("listening on %s" % url, reader.stats)


class ViewServer(ThreadingHTTPServer):
    daemon_threads = True  # an open event stream does not hold up the exit
    # SO_REUSEADDR: a restart binds at once despite connections in TIME_WAIT; a port another program listens
    # on is still refused (EADDRINUSE) on Linux.
    allow_reuse_address = True

    def __init__(self, address, state, page, stop):
        self.state, self.page, self.stop = state, page, stop
        super().__init__(address, ViewRequestHandler)


class ViewRequestHandler(BaseHTTPRequestHandler):
    server_version = "toposlam-view"

    def log_message(self, format, *args):  # no line per request on stderr
        pass

    def _send(self, code, content_type, body):
        self.send_response(code)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)

    def do_GET(self):
        path = self.path.split("?", 1)[0]
        state = self.server.state
        if path in ("/", "/index.html"):
            self._send(200, "text/html; charset=utf-8", self.server.page)
        elif path == "/state":
            self._send(200, "application/json", json.dumps(state.snapshot(), allow_nan=False).encode())
        elif path == "/events":
            self._events(state)
        elif path.startswith("/thumbnail/") and path.endswith(".jpg"):
            try:
                jpeg = state.thumbnail(int(path[len("/thumbnail/"):-len(".jpg")]))
            except ValueError:
                jpeg = None
            if jpeg is None:
                self._send(404, "text/plain", b"no such thumbnail\n")
            else:
                self.send_response(200)
                self.send_header("Content-Type", "image/jpeg")
                self.send_header("Content-Length", str(len(jpeg)))
                self.send_header("Cache-Control", "max-age=3600")  # a place's thumbnail never changes
                self.end_headers()
                self.wfile.write(jpeg)
        else:
            self._send(404, "text/plain", b"not found\n")

    def _events(self, state):
        self.send_response(200)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        sent = -1
        try:
            while not self.server.stop.is_set():
                version = state.wait_for_change(sent, EVENTS_KEEPALIVE_S)
                if version == sent:
                    self.wfile.write(b": keep-alive\n\n")
                else:
                    sent = version
                    self.wfile.write(b"data: " + json.dumps(state.snapshot(), allow_nan=False).encode() + b"\n\n")
                self.wfile.flush()
                self.server.stop.wait(EVENTS_MIN_INTERVAL_S)
        except (BrokenPipeError, ConnectionResetError):
            pass  # the page was closed


def fail(message, status):
    print("%s: error: %s" % (PROGRAM, message), file=sys.stderr, flush=True)
    sys.exit(status)


def parse_arguments(argv):
    parser = argparse.ArgumentParser(prog=PROGRAM, description="serve a live web page of toposlamd's map")
    parser.add_argument("--port", type=int, default=8080)
    parser.add_argument("--bind", default="127.0.0.1")
    parser.add_argument("--lcm-url", default=DEFAULT_URL)
    for kind in LiveViewState.KINDS:
        parser.add_argument("--%s-channel" % kind.replace("_", "-"), default="TOPOSLAM_" + kind.upper())
    args = parser.parse_args(argv)
    if not 0 < args.port < 65536:
        parser.error("--port %d is out of range (1..65535)" % args.port)
    try:
        parse_url(args.lcm_url)
    except ValueError as e:
        parser.error("--lcm-url: %s" % e)
    return args


def main(argv):
    args = parse_arguments(argv)
    page_path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "live_view.html")
    try:
        with open(page_path, "rb") as f:
            page = f.read()
    except OSError as e:
        fail("cannot read the page %s: %s" % (page_path, e.strerror), 1)

    state = LiveViewState()
    stop = threading.Event()
    try:
        server = ViewServer((args.bind, args.port), state, page, stop)
    except OSError as e:
        if e.errno == errno.EADDRINUSE:
            fail("port %d on %s is in use (another program listens there); choose another with --port"
                 % (args.port, args.bind), 1)
        if e.errno == errno.EACCES:
            fail("port %d on %s: permission denied (ports below 1024 need privileges); choose another with --port"
                 % (args.port, args.bind), 1)
        if isinstance(e, socket.gaierror) or e.errno == errno.EADDRNOTAVAIL:
            fail("--bind %s: not an address of this host (%s)" % (args.bind, e.strerror or e), 2)
        fail("cannot listen on %s port %d: %s" % (args.bind, args.port, e.strerror or e), 1)

    def on_stop_signal(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, on_stop_signal)
    signal.signal(signal.SIGINT, on_stop_signal)
    channels = {getattr(args, kind + "_channel"): kind for kind in LiveViewState.KINDS}
    reader = threading.Thread(target=read_lcm, args=(state, args.lcm_url, channels, stop), name="tsl-view-lcm",
                              daemon=True)
    reader.start()
    print("%s: serving http://%s:%d/ (LCM %s)" % (PROGRAM, args.bind, server.server_address[1], args.lcm_url),
          file=sys.stderr, flush=True)
    try:
        server.serve_forever(poll_interval=0.5)
    except KeyboardInterrupt:
        pass
    finally:
        stop.set()
        server.server_close()
        reader.join(2)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
