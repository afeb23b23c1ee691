#!/usr/bin/python3
"""Print toposlamd's place estimates (channel TOPOSLAM_PLACE, one per frame) without python3-lcm.

Usage: listen_places.py [COUNT] [LCM_URL]  (COUNT 0: until no message for 10 s; LCM_URL: toposlam.yaml's
lcm.url). Needs the package toposlam_lcm, installed with toposlam in /usr/lib/python3/dist-packages.
"""
import sys

from toposlam_lcm import place_t
from toposlam_lcm.udpm_reader import DEFAULT_URL, UdpmReader

count = int(sys.argv[1]) if len(sys.argv) > 1 else 0
seen = 0
try:
    with UdpmReader(sys.argv[2] if len(sys.argv) > 2 else DEFAULT_URL, channels=["TOPOSLAM_PLACE"]) as reader:
        for channel, payload in reader.messages(timeout=10):
            p = place_t.decode(payload)
            # node: of the last place whose filter step finished; now: the node this frame is back in (the
            # earlier frame it matches, p.match_frame, lies in it), -1 while it is no known node.
            print("frame %d place %d node %d p=%.2f now %d" % (p.frame, p.place, p.node, p.probability, p.match_node),
                  flush=True)
            seen += 1
            if seen == count:
                break
except KeyboardInterrupt:
    pass
sys.exit(0 if seen else 1)
