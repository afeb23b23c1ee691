"""A small LCM UDP-multicast reader in plain Python (standard library only).

Debian 12 ships no python3-lcm, so a Python program that wants toposlamd's messages reads the LCM
datagrams itself: join the multicast group of the LCM URL, take each datagram apart, put fragmented
messages back together, and hand out (channel, payload) pairs. Decode the payload with the generated
types of this package, e.g. ``toposlam_lcm.place_t.decode(payload)``.

Wire format (LCM's "UDP Multicast Protocol Description"; every integer big-endian):

- short message, one datagram: ``"LC02"`` magic (0x4c433032), u32 sequence number, the channel name
  NUL-terminated, then the payload.
- fragmented message, one datagram per fragment: ``"LC03"`` magic (0x4c433033), u32 sequence number,
  u32 payload size, u32 fragment offset (into the payload), u16 fragment number, u16 fragment count;
  the first fragment (number 0) then carries the channel name NUL-terminated; then the fragment's
  payload bytes. All fragments of a message share the sequence number.

LCM's C library sends up to about 64 kB in one short datagram on Linux and fragments larger messages.
Reassembly keeps at most ``max_pending`` incomplete messages (one per sender, as LCM's own receiver does:
a new message from a sender drops that sender's unfinished one) and refuses messages larger than
``max_message_bytes``, so garbage on the port cannot make the reader grow without bound. What it drops
is counted in ``stats``.

Thread-safety: a reader (and a Reassembler) is used by one thread at a time.
"""

import socket
import struct
import time
from collections import OrderedDict

DEFAULT_URL = "udpm://239.255.76.67:7667?ttl=0"  # toposlam.yaml's lcm.url, and LCM's own default group

MAGIC_SHORT = 0x4C433032  # "LC02"
MAGIC_FRAGMENT = 0x4C433033  # "LC03"
_SHORT_HEADER = struct.Struct(">II")  # magic, sequence number
_FRAGMENT_HEADER = struct.Struct(">IIIIHH")  # magic, sequence, payload size, offset, fragment, fragments
MAX_CHANNEL_BYTES = 255  # LCM 1.3 allows 63 (LCM_MAX_CHANNEL_NAME_LENGTH); longer names are accepted here


def parse_url(url):
    """Returns (group, port, ttl) of an LCM URL ``udpm://GROUP:PORT?ttl=N`` (missing parts: LCM's defaults).

    Raises ValueError for another provider or a malformed address.
    """
    provider, sep, rest = url.partition("://")
    if not sep or provider != "udpm":
        raise ValueError("not an LCM udpm:// URL: %r" % url)
    address, _, query = rest.partition("?")
    group, port, ttl = "239.255.76.67", 7667, 0
    if address:
        host, colon, port_text = address.rpartition(":")
        if not colon:
            host, port_text = address, ""
        if host:
            group = host
        if port_text:
            port = int(port_text)
    for option in filter(None, query.split("&")):
        key, _, value = option.partition("=")
        if key == "ttl":
            ttl = int(value)
    octets = group.split(".")
    if len(octets) != 4 or not all(o.isdigit() and int(o) < 256 for o in octets) or not 224 <= int(octets[0]) <= 239:
        raise ValueError("not an IPv4 multicast group in %r: %r" % (url, group))
    if not 0 < port < 65536:
        raise ValueError("port out of range in %r: %d" % (url, port))
    return group, port, ttl


class _Pending:
    """One fragmented message being put together."""

    __slots__ = ("sequence", "size", "count", "channel", "data", "received")

    def __init__(self, sequence, size, count):
        self.sequence = sequence
        self.size = size
        self.count = count
        self.channel = None
        self.data = bytearray(size)
        self.received = set()


class Reassembler:
    """Turns datagrams into (channel, payload) pairs. No sockets: tests feed it crafted bytes.

    stats: ``messages`` returned, ``fragments`` accepted, ``garbage`` (wrong magic, no NUL after the
    channel, inconsistent fragment header), ``truncated`` (shorter than its header), ``too_large``,
    ``dropped_incomplete`` (fragmented messages given up: replaced by the sender's next message or
    pushed out by ``max_pending`` others).
    """

    def __init__(self, max_pending=16, max_message_bytes=16 << 20):
        self.max_pending = max_pending
        self.max_message_bytes = max_message_bytes
        self._pending = OrderedDict()  # sender -> _Pending, oldest first
        self.stats = dict.fromkeys(
            ("messages", "fragments", "garbage", "truncated", "too_large", "dropped_incomplete"), 0)

    def feed(self, datagram, sender=None):
        """Takes one datagram; returns (channel, payload bytes) when it completes a message, else None."""
        if len(datagram) < 4:
            self.stats["truncated"] += 1
            return None
        magic = struct.unpack_from(">I", datagram)[0]
        if magic == MAGIC_SHORT:
            return self._short(datagram)
        if magic == MAGIC_FRAGMENT:
            return self._fragment(datagram, sender)
        self.stats["garbage"] += 1
        return None

    def _short(self, datagram):
        if len(datagram) < _SHORT_HEADER.size:
            self.stats["truncated"] += 1
            return None
        channel, end = self._channel(datagram, _SHORT_HEADER.size)
        if channel is None:
            return None
        self.stats["messages"] += 1
        return channel, bytes(datagram[end:])

    def _channel(self, datagram, start):
        """The NUL-terminated channel at start: (name, index after the NUL), or (None, 0) counted as garbage."""
        end = datagram.find(b"\0", start, start + MAX_CHANNEL_BYTES + 1)
        if end <= start:
            self.stats["garbage"] += 1
            return None, 0
        try:
            return bytes(datagram[start:end]).decode("utf-8"), end + 1
        except UnicodeDecodeError:
            self.stats["garbage"] += 1
            return None, 0

    def _fragment(self, datagram, sender):
        if len(datagram) < _FRAGMENT_HEADER.size:
            self.stats["truncated"] += 1
            return None
        _, sequence, size, offset, number, count = _FRAGMENT_HEADER.unpack_from(datagram)
        if count == 0 or number >= count or size == 0:
            self.stats["garbage"] += 1
            return None
        if size > self.max_message_bytes:
            self.stats["too_large"] += 1
            return None
        start = _FRAGMENT_HEADER.size
        channel = None
        if number == 0:
            channel, start = self._channel(datagram, start)
            if channel is None:
                return None
        chunk = memoryview(datagram)[start:]
        if offset + len(chunk) > size:
            self.stats["garbage"] += 1
            return None

        pending = self._pending.get(sender)
        if pending is not None and (pending.sequence != sequence or pending.size != size or pending.count != count):
            del self._pending[sender]  # the sender moved on: its unfinished message will not complete
            self.stats["dropped_incomplete"] += 1
            pending = None
        if pending is None:
            while len(self._pending) >= self.max_pending:
                self._pending.popitem(last=False)
                self.stats["dropped_incomplete"] += 1
            pending = self._pending[sender] = _Pending(sequence, size, count)
        if number in pending.received:
            return None  # a duplicate datagram
        pending.received.add(number)
        pending.data[offset:offset + len(chunk)] = chunk
        if channel is not None:
            pending.channel = channel
        self.stats["fragments"] += 1
        if len(pending.received) < count:
            return None
        del self._pending[sender]
        self.stats["messages"] += 1
        return pending.channel, bytes(pending.data)


class UdpmReader:
    """Receives LCM messages from a udpm:// URL: ``for channel, payload in reader.messages(timeout=5)``.

    channels: names to keep (None: all). The socket joins the group on construction, so messages sent
    after the constructor returns are received. Use as a context manager or call close().
    """

    def __init__(self, url=DEFAULT_URL, channels=None, receive_buffer_bytes=2 << 20, **reassembly):
        self.group, self.port, self.ttl = parse_url(url)
        self.channels = None if channels is None else frozenset(channels)
        self.reassembler = Reassembler(**reassembly)
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        try:
            # Several subscribers on one host share the port, as LCM's own receivers do.
            self._socket.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            if hasattr(socket, "SO_REUSEPORT"):
                self._socket.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
            self._socket.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, receive_buffer_bytes)
            self._socket.bind(("", self.port))
            membership = struct.pack("4s4s", socket.inet_aton(self.group), socket.inet_aton("0.0.0.0"))
            self._socket.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, membership)
        except OSError:
            self._socket.close()
            raise

    def read(self, timeout=None):
        """The next (channel, payload) on a kept channel, or None when none arrived within timeout seconds
        (None: wait for ever)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            if deadline is not None:
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._socket.settimeout(left)
            else:
                self._socket.settimeout(None)
            try:
                datagram, sender = self._socket.recvfrom(65536)
            except socket.timeout:
                return None
            message = self.reassembler.feed(datagram, sender)
            if message is not None and (self.channels is None or message[0] in self.channels):
                return message

    def messages(self, timeout=None):
        """Yields (channel, payload) until no message arrives for timeout seconds."""
        while True:
            message = self.read(timeout)
            if message is None:
                return
            yield message

    @property
    def stats(self):
        return self.reassembler.stats

    def close(self):
        self._socket.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
