"""The pure-Python LCM reader (platform/lcm/python/udpm_reader.py) and the generated Python types, on crafted
datagrams: no network. Run by ctest (test_platform_udpm_reader) as
`PYTHONPATH=<build>/platform/lcm/generated/python python3 -m unittest -v test_udpm_reader`.

The fragments are cut the way LCM's C library cuts them (lcm_udpm.c): the first datagram carries the
header, the channel and fragment_size - (len(channel) + 1) payload bytes; the others fragment_size bytes.
"""
import os
import random
import struct
import unittest

import toposlam_lcm
from toposlam_lcm.udpm_reader import MAGIC_FRAGMENT, MAGIC_SHORT, Reassembler, parse_url

CORPUS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "fuzz", "corpus", "lcm_messages")


def short_datagram(channel, payload, sequence=7):
    return struct.pack(">II", MAGIC_SHORT, sequence) + channel.encode() + b"\0" + payload


def fragments(channel, payload, sequence=9, fragment_size=1400):
    """LCM's fragmented datagrams of one message, in sending order."""
    first = fragment_size - (len(channel) + 1)
    pieces = [(0, payload[:first])]
    offset = first
    while offset < len(payload):
        pieces.append((offset, payload[offset:offset + fragment_size]))
        offset += fragment_size
    out = []
    for number, (offset, data) in enumerate(pieces):
        header = struct.pack(">IIIIHH", MAGIC_FRAGMENT, sequence, len(payload), offset, number, len(pieces))
        out.append(header + (channel.encode() + b"\0" if number == 0 else b"") + data)
    return out


def feed_all(reassembler, datagrams, sender=("127.0.0.1", 40000)):
    return [m for m in (reassembler.feed(d, sender) for d in datagrams) if m is not None]


class ParseUrl(unittest.TestCase):
    def test_given_the_daemon_default_url_then_group_port_and_ttl(self):
        self.assertEqual(parse_url("udpm://239.255.76.67:7667?ttl=0"), ("239.255.76.67", 7667, 0))
        self.assertEqual(parse_url("udpm://239.1.2.3:9000?ttl=1&recv_buf_size=2097152"), ("239.1.2.3", 9000, 1))

    def test_given_missing_parts_then_lcm_defaults(self):
        self.assertEqual(parse_url("udpm://"), ("239.255.76.67", 7667, 0))
        self.assertEqual(parse_url("udpm://239.9.9.9"), ("239.9.9.9", 7667, 0))

    def test_given_another_provider_or_a_unicast_address_then_value_error(self):
        for bad in ("memq://", "file:///tmp/log?mode=r", "udpm://10.0.0.1:7667", "udpm://239.1.1:7667",
                    "udpm://239.255.76.67:0", "239.255.76.67:7667"):
            with self.assertRaises(ValueError, msg=bad):
                parse_url(bad)


class ShortMessages(unittest.TestCase):
    def test_given_a_short_datagram_then_channel_and_payload(self):
        r = Reassembler()
        self.assertEqual(r.feed(short_datagram("TOPOSLAM_PLACE", b"\x01\x02\x03")), ("TOPOSLAM_PLACE", b"\x01\x02\x03"))
        self.assertEqual(r.feed(short_datagram("EMPTY", b"")), ("EMPTY", b""))
        self.assertEqual(r.stats["messages"], 2)

    def test_given_an_encoded_place_t_then_the_generated_type_decodes_it(self):
        place = toposlam_lcm.place_t()
        place.frame, place.place, place.node, place.probability = 1234, 5, 3, 0.75
        alternative = toposlam_lcm.place_alternative_t()
        alternative.node, alternative.probability = 1, 0.25
        place.num_alternatives, place.alternatives = 1, [alternative]
        channel, payload = Reassembler().feed(short_datagram("TOPOSLAM_PLACE", place.encode()))
        decoded = toposlam_lcm.place_t.decode(payload)
        self.assertEqual((channel, decoded.frame, decoded.place, decoded.node), ("TOPOSLAM_PLACE", 1234, 5, 3))
        self.assertAlmostEqual(decoded.probability, 0.75)
        self.assertEqual(decoded.alternatives[0].node, 1)

    def test_given_the_cpp_encoded_seeds_then_python_decodes_them_same_type_hashes(self):
        # tests/fuzz/corpus/lcm_messages/<kind>: byte 0 the kind, then a message encoded by the C++ types
        # (fuzz_make_seeds). Decoding checks the 8-byte type hash, so Python and C++ agree on every type,
        # topology_edge_t's renamed fields included.
        for name, cls in (("place", toposlam_lcm.place_t), ("place_event", toposlam_lcm.place_event_t),
                          ("status", toposlam_lcm.status_t), ("topology", toposlam_lcm.topology_t),
                          ("motion", toposlam_lcm.motion_t)):
            with open(os.path.join(CORPUS, name), "rb") as f:
                cls.decode(f.read()[1:])
        edge = toposlam_lcm.topology_edge_t()
        edge.from_node, edge.to_node, edge.count = 2, 7, 3
        topology = toposlam_lcm.topology_t()
        topology.num_edges, topology.edges = 1, [edge]
        back = toposlam_lcm.topology_t.decode(topology.encode()).edges[0]
        self.assertEqual((back.from_node, back.to_node, back.count), (2, 7, 3))


class Garbage(unittest.TestCase):
    def test_given_garbage_and_truncated_headers_then_counted_and_nothing_returned(self):
        r = Reassembler()
        rng = random.Random(1)
        datagrams = [bytes(rng.randrange(256) for _ in range(rng.randrange(0, 200))) for _ in range(200)]
        datagrams += [
            b"",
            b"LC0",  # shorter than a magic
            b"LC02\x00\x00",  # a short header cut at 6 bytes
            struct.pack(">IIIIH", MAGIC_FRAGMENT, 1, 10, 0, 0),  # a fragment header cut at 18 bytes
            short_datagram("X", b"")[:8],  # a short header with no channel
            struct.pack(">II", MAGIC_SHORT, 1) + b"NO_NUL_AFTER_THE_CHANNEL",
            struct.pack(">II", MAGIC_SHORT, 1) + b"\0payload",  # an empty channel name
            struct.pack(">II", MAGIC_SHORT, 1) + b"A" * 300 + b"\0",  # a channel longer than LCM allows
            struct.pack(">II", MAGIC_SHORT, 1) + b"\xff\xfe\0",  # not UTF-8
            struct.pack(">IIIIHH", MAGIC_FRAGMENT, 1, 10, 0, 2, 2) + b"x",  # fragment 2 of 2
            struct.pack(">IIIIHH", MAGIC_FRAGMENT, 1, 10, 0, 0, 0) + b"C\0x",  # 0 fragments
            struct.pack(">IIIIHH", MAGIC_FRAGMENT, 1, 10, 8, 1, 2) + b"xyz",  # past the payload size
        ]
        self.assertEqual(feed_all(r, datagrams), [])
        self.assertEqual(r.stats["messages"], 0)
        self.assertGreaterEqual(r.stats["garbage"], 190)
        self.assertGreaterEqual(r.stats["truncated"], 4)
        # The reader still works after all that.
        self.assertEqual(r.feed(short_datagram("OK", b"1")), ("OK", b"1"))

    def test_given_a_fragment_claiming_more_than_the_limit_then_refused_without_allocating(self):
        r = Reassembler(max_message_bytes=1 << 20)
        header = struct.pack(">IIIIHH", MAGIC_FRAGMENT, 1, 0xFFFFFFFF, 0, 0, 3)
        self.assertIsNone(r.feed(header + b"C\0data"))
        self.assertEqual(r.stats["too_large"], 1)


class Fragments(unittest.TestCase):
    payload = bytes(random.Random(2).randrange(256) for _ in range(200_000))  # 143 fragments of 1400 bytes

    def test_given_fragments_in_order_then_one_message_equal_to_the_payload(self):
        r = Reassembler()
        datagrams = fragments("TOPOSLAM_TOPOLOGY", self.payload)
        self.assertEqual(len(datagrams), 143)
        self.assertEqual(feed_all(r, datagrams), [("TOPOSLAM_TOPOLOGY", self.payload)])
        self.assertEqual((r.stats["fragments"], r.stats["messages"]), (143, 1))

    def test_given_fragments_out_of_order_with_duplicates_then_reassembled_once(self):
        r = Reassembler()
        datagrams = fragments("BIG", self.payload)
        shuffled = datagrams[:]
        random.Random(3).shuffle(shuffled)
        shuffled.remove(datagrams[0])
        shuffled.append(datagrams[0])  # the fragment with the channel comes last
        shuffled.insert(10, shuffled[5])  # a duplicate
        self.assertEqual(feed_all(r, shuffled), [("BIG", self.payload)])
        self.assertEqual(r.stats["messages"], 1)

    def test_given_a_topology_t_over_several_fragments_then_the_generated_type_decodes_it(self):
        topology = toposlam_lcm.topology_t()
        topology.map_revision, topology.particles = 41, 500
        for i in range(400):
            node = toposlam_lcm.topology_node_t()
            node.id, node.num_places, node.places = i, 3, [i, i + 400, i + 800]
            node.num_representatives, node.representative_frames = 1, [10 * i]
            topology.nodes.append(node)
            edge = toposlam_lcm.topology_edge_t()
            edge.from_node, edge.to_node, edge.count = i, (i + 1) % 400, 1
            topology.edges.append(edge)
        topology.num_nodes, topology.num_edges = 400, 400
        payload = topology.encode()
        datagrams = fragments("TOPOSLAM_TOPOLOGY", payload, fragment_size=1000)
        self.assertGreater(len(datagrams), 10)
        [(channel, got)] = feed_all(Reassembler(), reversed(datagrams))
        decoded = toposlam_lcm.topology_t.decode(got)
        self.assertEqual((decoded.map_revision, decoded.num_nodes, list(decoded.nodes[399].places)),
                         (41, 400, [399, 799, 1199]))
        self.assertEqual((decoded.edges[399].from_node, decoded.edges[399].to_node), (399, 0))

    def test_given_two_senders_interleaved_then_both_messages(self):
        r = Reassembler()
        a = fragments("A", self.payload[:5000], sequence=1)
        b = fragments("B", self.payload[5000:12000], sequence=1)
        got = []
        for i in range(max(len(a), len(b))):
            for sender, datagrams in ((("10.0.0.1", 1), a), (("10.0.0.2", 1), b)):
                if i < len(datagrams):
                    m = r.feed(datagrams[i], sender)
                    if m:
                        got.append(m)
        self.assertEqual(sorted(got), [("A", self.payload[:5000]), ("B", self.payload[5000:12000])])

    def test_given_a_lost_fragment_then_the_message_is_dropped_when_the_sender_sends_the_next(self):
        r = Reassembler()
        first = fragments("LOSSY", self.payload[:10000], sequence=20)
        del first[3]  # lost on the way
        second = fragments("LOSSY", self.payload[10000:20000], sequence=21)
        self.assertEqual(feed_all(r, first + second), [("LOSSY", self.payload[10000:20000])])
        self.assertEqual(r.stats["dropped_incomplete"], 1)
        # A short message in between does not disturb a fragmented one being put together.
        third = fragments("LOSSY", self.payload[:3000], sequence=22)
        got = feed_all(r, third[:1] + [short_datagram("SMALL", b"s", 23)] + third[1:])
        self.assertEqual(got, [("SMALL", b"s"), ("LOSSY", self.payload[:3000])])

    def test_given_more_unfinished_senders_than_max_pending_then_the_oldest_dropped_memory_bounded(self):
        r = Reassembler(max_pending=2)
        for port in range(5):  # five senders, each sends only its first fragment
            r.feed(fragments("X", self.payload[:5000], sequence=port)[0], ("10.0.0.1", port))
        self.assertEqual(len(r._pending), 2)
        self.assertEqual(r.stats["dropped_incomplete"], 3)


if __name__ == "__main__":
    unittest.main()
