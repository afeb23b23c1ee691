"""LiveViewState of `toposlam view` (src/apps/toposlam/view/live_view.py), fed encoded LCM messages
directly: no sockets, no daemon. Run by ctest as test_live_view_state (PYTHONPATH: the build tree's
toposlam_lcm and the view's folder)."""
import json
import math
import unittest

import toposlam_lcm
from live_view import LiveViewState


def topology(revision, nodes, edges, current):
    t = toposlam_lcm.topology_t()
    t.map_revision, t.probability, t.particles, t.current_node = revision, 0.75, 500, current
    for node_id, places in nodes:
        n = toposlam_lcm.topology_node_t()
        n.id, n.places, n.num_places = node_id, places, len(places)
        n.representative_frames, n.num_representatives = [10 * p for p in places], len(places)
        t.nodes.append(n)
    for a, b in edges:
        e = toposlam_lcm.topology_edge_t()
        e.from_node, e.to_node, e.count = a, b, 1
        t.edges.append(e)
    t.num_nodes, t.num_edges = len(t.nodes), len(t.edges)
    return t.encode()


def place_event(place, node, is_new, jpeg=b"\xff\xd8fake-jpeg\xff\xd9"):
    e = toposlam_lcm.place_event_t()
    e.place, e.node, e.is_new, e.probability = place, node, is_new, 0.5
    e.first_frame, e.last_frame, e.representative_frame = 100 * place, 100 * place + 99, 100 * place + 50
    e.thumbnail_width, e.thumbnail_height, e.jpeg, e.jpeg_size = 160, 120, jpeg, len(jpeg)
    e.map_revision = place + 1
    return e.encode()


def place_estimate(frame, node, match_node):
    p = toposlam_lcm.place_t()
    p.frame, p.place, p.node, p.probability, p.lambda2 = frame, 2, node, 0.5, 0.1
    p.match_frame, p.match_place, p.match_node = (50, 0, match_node) if match_node >= 0 else (-1, -1, -1)
    return p.encode()


class LiveViewStateTest(unittest.TestCase):
    def test_given_a_run_when_fed_its_messages_then_the_snapshot_shows_nodes_thumbnails_current_and_revisits(self):
        state = LiveViewState()
        for place, node, is_new in ((0, 0, True), (1, 1, True), (2, 0, False)):
            self.assertTrue(state.accept("place_event", place_event(place, node, is_new)))
        self.assertTrue(state.accept("topology", topology(3, [(0, [0, 2]), (1, [1])], [(0, 1), (1, 0)], current=0)))
        s = state.snapshot()
        self.assertEqual([n["id"] for n in s["nodes"]], [0, 1])
        self.assertEqual([n["thumbnail"] for n in s["nodes"]], [0, 1])  # each node's earliest place
        self.assertEqual(len(s["edges"]), 2)
        self.assertEqual((s["current_node"], s["current_kind"]), (0, "last place"))
        self.assertEqual(len(s["revisits"]), 1)
        self.assertEqual((s["revisits"][0]["place"], s["revisits"][0]["matched_place"]), (2, 0))
        self.assertEqual(state.thumbnail(2), b"\xff\xd8fake-jpeg\xff\xd9")
        self.assertIsNone(state.thumbnail(7))

        # The frame-level answer: back at node 1 now, whatever the last place's node.
        self.assertTrue(state.accept("place", place_estimate(250, node=0, match_node=1)))
        s = state.snapshot()
        self.assertEqual((s["current_node"], s["current_kind"]), (1, "back at"))
        self.assertTrue(state.accept("place", place_estimate(251, node=0, match_node=-1)))
        self.assertEqual(state.snapshot()["current_node"], 0)
        self.assertEqual(state.snapshot()["messages"], {"place": 2, "place_event": 3, "topology": 1, "status": 0})

    def test_given_garbage_on_every_channel_then_it_is_counted_and_changes_nothing_else(self):
        state = LiveViewState()
        state.accept("topology", topology(1, [(0, [0])], [], current=0))
        good = topology(2, [(0, [0]), (1, [1])], [(0, 1)], current=1)
        for kind, payload in (("topology", b""), ("topology", good[:-3]), ("topology", b"\x00" * 8 + good[8:]),
                              ("place", b"not a place_t"), ("place_event", place_event(5, 0, True)[:20]),
                              ("status", topology(1, [], [], 0))):
            self.assertFalse(state.accept(kind, payload), kind)
        s = state.snapshot()
        self.assertEqual(s["undecodable"], {"place": 1, "place_event": 1, "topology": 3, "status": 1})
        self.assertEqual(s["messages"]["topology"], 1)
        self.assertEqual(len(s["nodes"]), 1)  # still the first topology
        self.assertIsNone(s["place"])
        self.assertTrue(s["last_error"].startswith("status: "))

    def test_given_nan_in_a_status_and_a_place_then_the_snapshot_is_still_json(self):
        state = LiveViewState()
        status = toposlam_lcm.status_t()
        status.state, status.source_state, status.motion_state = "running", "simulator", "none"
        status.fps, status.latency_median_ms, status.latency_p99_ms = 30.0, math.nan, math.inf
        self.assertTrue(state.accept("status", status.encode()))
        p = toposlam_lcm.place_t()
        p.frame, p.place, p.node, p.probability, p.latency_ms, p.match_node = 3, -1, -1, math.nan, 1.5, -1
        self.assertTrue(state.accept("place", p.encode()))
        s = json.loads(json.dumps(state.snapshot(), allow_nan=False))
        self.assertEqual((s["status"]["fps"], s["status"]["latency_median_ms"], s["status"]["latency_p99_ms"]),
                         (30.0, None, None))
        self.assertEqual((s["place"]["probability"], s["place"]["latency_ms"]), (None, 1.5))
        self.assertEqual(s["current_node"], -1)

    def test_given_a_thumbnail_budget_then_the_oldest_thumbnails_go_first(self):
        state = LiveViewState(thumbnail_bytes_kept=250)
        for place in range(5):
            state.accept("place_event", place_event(place, place, True, jpeg=bytes(100)))
        self.assertEqual(state.thumbnails_dropped, 3)
        self.assertIsNone(state.thumbnail(2))
        self.assertEqual(len(state.thumbnail(4)), 100)


if __name__ == "__main__":
    unittest.main()
