"""What e2e_examples_listen_places (check_listen_places.sh) runs in Python, with the package toposlam_lcm of
the build tree (types + udpm_reader) on PYTHONPATH:

  subscriber_check.py probe URL                 exit 0 if a datagram sent to URL's group comes back, else 77
  subscriber_check.py large-log LOG             write an LCM log of one message too large for one datagram
  subscriber_check.py collect URL READY         read every channel of toposlamd's run (and the large message)
                                                with udpm_reader, assert on what was decoded, print numbers
  subscriber_check.py example-output FILE N     the output of an example: >= N lines, frames increasing

Exit status: 0 ok, 1 an assertion failed (the message says which), 77 no multicast here.
"""
import json
import math
import os
import socket
import struct
import sys
import time

import toposlam_lcm
from toposlam_lcm.udpm_reader import UdpmReader, parse_url

FRAMES = 1618  # sim:office?route=loop2
LARGE_CHANNEL = "TOPOSLAM_E2E_LARGE"


def fail(message):
    print("FAIL: " + message, flush=True)
    sys.exit(1)


def check(condition, message):
    if not condition:
        fail(message)


def probe(url):
    """Multicast on this host: join the group, send one datagram to it, receive it."""
    group, port, _ = parse_url(url)
    try:
        with UdpmReader(url) as reader:
            out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            out.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
            out.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
            out.sendto(struct.pack(">II", 0x4C433032, 0) + b"TOPOSLAM_E2E_PROBE\0x", (group, port))
            out.close()
            if reader.read(timeout=3) == ("TOPOSLAM_E2E_PROBE", b"x"):
                return 0
    except OSError as e:
        print("SKIP: multicast unavailable: %s" % e)
        return 77
    print("SKIP: a datagram sent to %s:%d did not come back (no multicast route?)" % (group, port))
    return 77


def large_topology():
    """A real topology_t of about 300 kB: liblcm sends it in several LC03 fragments (65487 bytes each)."""
    t = toposlam_lcm.topology_t()
    t.map_revision, t.probability, t.particles = 7, 0.5, 500
    for i in range(5000):
        node = toposlam_lcm.topology_node_t()
        node.id, node.num_places, node.places = i, 4, [i, i + 5000, i + 10000, i + 15000]
        node.num_representatives, node.representative_frames = 4, [i, 2 * i, 3 * i, 4 * i]
        t.nodes.append(node)
        edge = toposlam_lcm.topology_edge_t()
        edge.from_node, edge.to_node, edge.count = i, (i + 1) % 5000, 1 + i % 3
        t.edges.append(edge)
    t.num_nodes, t.num_edges = len(t.nodes), len(t.edges)
    return t.encode()


def large_log(path):
    """An LCM log file (LCM's log format: sync word 0xEDA1DA01, event number, timestamp in microseconds,
    channel and data lengths, channel, data) holding one large message, for lcm-logplayer."""
    data = large_topology()
    channel = LARGE_CHANNEL.encode()
    with open(path, "wb") as f:
        f.write(struct.pack(">IqqII", 0xEDA1DA01, 0, int(time.time() * 1e6), len(channel), len(data)) + channel + data)
    return 0


def collect(url, ready_path):
    places, events, topologies, statuses, large = [], [], [], [], None
    started = time.monotonic()
    with UdpmReader(url) as reader:
        with open(ready_path, "w") as ready:
            ready.write("ready\n")
        finished = False
        while not (finished and large is not None) and time.monotonic() - started < 150:
            message = reader.read(timeout=30)
            if message is None:
                break
            channel, payload = message
            if channel == "TOPOSLAM_PLACE":
                places.append(toposlam_lcm.place_t.decode(payload))
            elif channel == "TOPOSLAM_PLACE_EVENT":
                events.append(toposlam_lcm.place_event_t.decode(payload))
            elif channel == "TOPOSLAM_TOPOLOGY":
                topologies.append(toposlam_lcm.topology_t.decode(payload))
            elif channel == "TOPOSLAM_STATUS":
                statuses.append(toposlam_lcm.status_t.decode(payload))
                finished = statuses[-1].state == "finished"
            elif channel == LARGE_CHANNEL:
                large = payload
        stats = dict(reader.stats)

    # Place estimates: one per frame, in order, fields in range.
    frames = [p.frame for p in places]
    # Lossless queues publish all 1618; UDP may lose a few on a loaded host (the other e2e tests allow 5 %).
    check(len(places) >= 0.95 * FRAMES, "%d place messages decoded, expected >= 95 %% of %d" % (len(places), FRAMES))
    check(all(b > a for a, b in zip(frames, frames[1:])), "place frame numbers not increasing")
    check(0 <= frames[0] and frames[-1] < FRAMES, "frames %d..%d outside 0..%d" % (frames[0], frames[-1], FRAMES - 1))
    for p in places:
        check(-1 <= p.place and -1 <= p.node and 0.0 <= p.probability <= 1.0 and p.latency_ms >= 0.0,
              "place_t out of range: frame %d place %d node %d p=%f latency %f" % (p.frame, p.place, p.node, p.probability, p.latency_ms))
        check(-1 <= p.match_frame < p.frame and (p.match_frame >= 0 or (p.match_node == -1 and p.match_place == -1)),
              "place_t's match out of range: frame %d match_frame %d place %d node %d" % (p.frame, p.match_frame, p.match_place, p.match_node))
        check(p.num_alternatives == len(p.alternatives), "num_alternatives %d, %d alternatives" % (p.num_alternatives, len(p.alternatives)))
        check(math.isnan(p.lambda2) or p.lambda2 >= -1e-6, "lambda2 %f < 0" % p.lambda2)
    # The second lap is back where the first went: most of its frames name the earlier frame and its node.
    back = [p for p in places if p.frame >= FRAMES // 2 and p.match_frame >= 0 and p.match_node >= 0]
    check(len(back) >= 0.5 * sum(1 for p in places if p.frame >= FRAMES // 2),
          "only %d second-lap frames name an earlier frame's node" % len(back))
    revisions = [p.map_revision for p in places]
    check(all(b >= a for a, b in zip(revisions, revisions[1:])), "map_revision decreased")
    mapped = [p for p in places if p.place >= 0]
    check(len({p.place for p in mapped}) >= 10, "%d places stepped, expected >= 10" % len({p.place for p in mapped}))

    # Place events: the places, with their thumbnails.
    # 24 places on this route (13 nodes, 11 revisits) when measured; the bounds leave room for a lost datagram.
    check(len(events) >= 20, "%d place events, expected >= 20" % len(events))
    check(sum(not e.is_new for e in events) >= 3, "%d revisits, expected >= 3" % sum(not e.is_new for e in events))
    for e in events:
        check(e.first_frame <= e.representative_frame <= e.last_frame < FRAMES, "event frames %d <= %d <= %d" % (e.first_frame, e.representative_frame, e.last_frame))
        check(e.jpeg_size == len(e.jpeg) > 0 and bytes(e.jpeg[:2]) == b"\xff\xd8", "place %d: thumbnail is not a JPEG" % e.place)
    # The topology: nodes and edges consistent.
    check(len(topologies) >= 10, "%d topology_t decoded, expected >= 10" % len(topologies))
    last = topologies[-1]
    ids = {n.id for n in last.nodes}
    check(last.num_nodes == len(last.nodes) >= 3 and last.num_edges == len(last.edges) >= 2,
          "last topology: %d nodes, %d edges" % (last.num_nodes, last.num_edges))
    check(all(e.from_node in ids and e.to_node in ids and e.count >= 1 for e in last.edges), "an edge names an unknown node")
    check(0.0 < last.probability <= 1.0 and last.particles > 0, "topology probability %f particles %d" % (last.probability, last.particles))
    check(last.current_node in ids, "current node %d is not a node" % last.current_node)
    check(sum(n.num_places for n in last.nodes) == max(e.place for e in events) + 1, "the nodes' places are not places 0..N-1")
    # Status: the run finished.
    check(statuses and statuses[-1].state == "finished", "no 'finished' status (last: %s)" % (statuses[-1].state if statuses else None))
    # The large message from liblcm (lcm-logplayer), fragmented by LCM and put together by udpm_reader.
    check(large == large_topology(), "the large message (%s bytes) differs from what was sent" % (None if large is None else len(large)))
    check(stats["fragments"] >= 2, "the large message came in %d fragments" % stats["fragments"])
    decoded = toposlam_lcm.topology_t.decode(large)
    check((decoded.num_nodes, decoded.edges[4999].from_node, decoded.edges[4999].to_node) == (5000, 4999, 0), "large topology_t decoded wrong")

    print(json.dumps({
        "seconds": round(time.monotonic() - started, 1),
        "place_messages": len(places), "frames": [frames[0], frames[-1]], "places": len({p.place for p in mapped}),
        "place_events": len(events), "new_nodes": sum(e.is_new for e in events),
        "revisits": sum(not e.is_new for e in events),
        "thumbnail_bytes": [min(e.jpeg_size for e in events), max(e.jpeg_size for e in events)],
        "topologies": len(topologies), "last_topology": {"nodes": last.num_nodes, "edges": last.num_edges,
                                                           "probability": round(last.probability, 3)},
        "statuses": len(statuses), "large_message_bytes": len(large), "reader": stats}), flush=True)
    return 0


def example_output(path, minimum):
    with open(path) as f:
        lines = [line.split() for line in f if line.strip()]
    check(len(lines) >= minimum, "%s: %d lines, expected >= %d" % (path, len(lines), minimum))
    frames = []
    for words in lines:
        check(len(words) == 9 and words[0::2][:3] == ["frame", "place", "node"] and words[6].startswith("p=")
              and words[7] == "now", "%s: unexpected line %r" % (path, " ".join(words)))
        frame, place, node, p, now = int(words[1]), int(words[3]), int(words[5]), float(words[6][2:]), int(words[8])
        check(0 <= frame < FRAMES and place >= -1 and node >= -1 and 0.0 <= p <= 1.0 and now >= -1,
              "%s: out of range: %r" % (path, " ".join(words)))
        frames.append(frame)
    check(all(b > a for a, b in zip(frames, frames[1:])), "%s: frames not increasing" % path)
    check(max(int(w[3]) for w in lines) >= 0, "%s: no place stepped in %d lines" % (path, len(lines)))
    print("%s: %d lines, frames %d..%d, last place %s node %s" % (os.path.basename(path), len(lines), frames[0], frames[-1], lines[-1][3], lines[-1][5]))
    return 0


if __name__ == "__main__":
    command, args = sys.argv[1], sys.argv[2:]
    if command == "probe":
        sys.exit(probe(args[0]))
    if command == "large-log":
        sys.exit(large_log(args[0]))
    if command == "collect":
        sys.exit(collect(args[0], args[1]))
    if command == "example-output":
        sys.exit(example_output(args[0], int(args[1])))
    fail("unknown command " + command)
