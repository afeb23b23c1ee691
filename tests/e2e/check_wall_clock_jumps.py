#!/usr/bin/env python3
"""The real toposlamd while its wall clock jumps (issue 19, docs/reliability.md "Clock jumps").

wall_clock_jumps.so (LD_PRELOAD) makes the daemon's wall clock honest, an hour behind, a day ahead, honest
again, every 0.5 s, as NTP stepping the clock of a robot without RTC would, over and over. Everything that
measures a duration (watchdog pings, status rate, periodic map saves, the filter budget) runs on
CLOCK_MONOTONIC, so for 8 s the daemon must ping the watchdog about every 0.5 s (neither an hour's silence
nor a flood), report a frame rate near the source's 10 fps, save its map about once a second, and stop
cleanly with the map saved. After SIGTERM this test, unlike systemd, no longer reads the notify socket: the
daemon must stop all the same (its notifications never block; a stop that took more than a second under
load once hung here in sd_notify). Its log's own time stamps (wall clock) show the jumps: the library was in force.

Usage: check_wall_clock_jumps.py TOPOSLAMD WALL_CLOCK_JUMPS_SO WORK_DIR     (prints PASS or FAIL: ...)
"""
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time

RUN_S = 8.0
PERIOD_S = 0.5


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def threadsWaitingIn(pid):
    """Each thread's name and the kernel function it sleeps in (a hang's first clue), from /proc."""
    out = []
    try:
        for tid in sorted(os.listdir("/proc/%d/task" % pid)):
            base = "/proc/%d/task/%s/" % (pid, tid)
            out.append("%s %s" % (open(base + "comm").read().strip(), open(base + "wchan").read().strip()))
    except OSError as e:
        out.append("(cannot read /proc: %s)" % e)
    return ", ".join(out)


def main():
    toposlamd, shim, work = sys.argv[1:4]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    env = dict(os.environ, LD_PRELOAD=shim, TOPOSLAM_WALL_JUMP_PERIOD_S=str(PERIOD_S))

    # The library works: `date` under it sees the clock go back an hour and forward a day.
    seen = []
    end = time.monotonic() + 4 * PERIOD_S
    while time.monotonic() < end:
        seen.append(int(subprocess.check_output(["date", "+%s"], env=env)))
        time.sleep(PERIOD_S / 5)
    steps = [b - a for a, b in zip(seen, seen[1:])]
    if min(steps) > -3000 or max(steps) < 80000:
        fail("the wall-clock library has no effect: `date` steps %s" % steps)

    notify_path = os.path.join(work, "notify.sock")
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(notify_path)
    sock.settimeout(0.1)
    env.update(NOTIFY_SOCKET=notify_path, WATCHDOG_USEC="1000000")  # pinged every 0.5 s
    map_path = os.path.join(work, "map.tsm")
    log_path = os.path.join(work, "toposlamd.log")
    with open(log_path, "w") as log:
        daemon = subprocess.Popen(
            [toposlamd, "--source", "sim:office?route=loop2&fps=10&size=160x120&rate=10", "--map", map_path,
             "--no-map-load", "--save-period", "1", "--lcm-url", "memq://"],
            env=env, stdout=log, stderr=subprocess.STDOUT)
    pings, statuses = [], []
    ready_at = None
    end = time.monotonic() + 30.0  # the start, however slow, then RUN_S of running
    while time.monotonic() < end and daemon.poll() is None:
        try:
            message = sock.recv(4096).decode(errors="replace")
        except socket.timeout:
            continue
        now = time.monotonic()
        if "READY=1" in message and ready_at is None:
            ready_at = now
            end = now + RUN_S
        if "WATCHDOG=1" in message:
            pings.append(now)
        for line in message.splitlines():
            if line.startswith("STATUS=running:"):
                statuses.append(line)
    if daemon.poll() is not None:
        fail("toposlamd ended by itself (exit %s): %s" % (daemon.returncode, open(log_path).read()[-2000:]))
    daemon.send_signal(signal.SIGTERM)
    try:
        rc = daemon.wait(timeout=60)
    except subprocess.TimeoutExpired:
        where = threadsWaitingIn(daemon.pid)
        daemon.kill()
        fail("toposlamd did not stop within 60 s of SIGTERM; its threads wait in: %s; its log ends: %s"
             % (where, open(log_path).read()[-2000:]))
    log = open(log_path).read()
    if ready_at is None:
        fail("no READY=1 from toposlamd")
    if rc != 0:
        fail("toposlamd exit %d after SIGTERM: %s" % (rc, log[-2000:]))

    # Watchdog: about RUN_S / PERIOD_S pings; no hour-long silence (a wait on the wall clock stepped back)
    # and no flood (one stepped forward).
    gaps = [b - a for a, b in zip(pings, pings[1:])]
    expected = RUN_S / PERIOD_S
    if not (0.5 * expected <= len(pings) <= 3 * expected) or (gaps and max(gaps) > 3.0):
        fail("%d watchdog pings in %.0f s (expected about %.0f), longest gap %.1f s"
             % (len(pings), RUN_S, expected, max(gaps) if gaps else -1))
    # Status: the frame rate is measured on the monotonic clock (10 fps source).
    rates = [float(m.group(1)) for m in (re.match(r"STATUS=running: ([0-9.]+) fps", s) for s in statuses) if m]
    if len(rates) < 3 or not all(0.0 <= r <= 30.0 for r in rates) or max(rates) < 5.0:
        fail("status frame rates %s (a 10 fps source)" % rates)
    # Periodic saves every second (monotonic), and the last one at stop.
    saves = log.count("map saved to")
    if saves < 3 or not os.path.getsize(map_path):
        fail("%d map saves in %.0f s with --save-period 1" % (saves, RUN_S))
    # The daemon's own log stamps (wall clock) went back: it ran under the jumping clock.
    stamps = [time.mktime(time.strptime(m.group(1), "%Y-%m-%d %H:%M:%S"))
              for m in re.finditer(r"^\[(\d{4}-\d\d-\d\d \d\d:\d\d:\d\d)\.\d+\]", log, re.M)]
    if not any(b - a < -3000 for a, b in zip(stamps, stamps[1:])):
        fail("the daemon's log shows no wall-clock step back: the library was not in force")
    print("toposlamd under a wall clock jumping -1 h / +1 day every %.1f s: %d watchdog pings in %.0f s "
          "(longest gap %.2f s), status %.1f-%.1f fps, %d map saves, exit 0"
          % (PERIOD_S, len(pings), RUN_S, max(gaps), min(rates), max(rates), saves))
    print("PASS")


if __name__ == "__main__":
    main()
