"""Load, on loopback only, bounded in time: 2,000 open long-polls and 500
clients sending their headers a byte a second (reconnecting when cut) while
a job renders. Throughout, /healthz answers within 100 ms at the 99th
percentile, new jobs are accepted, wrk on the GET endpoints sees no error;
then SIGTERM answers every wait and the daemon exits within 5 s.

The load lasts until every slow client has been cut at the daemon's 10 s
header deadline (about 11 s), or LOAD_SECONDS if longer. The clients come
from 40 loopback addresses (127.0.1.x), since one address may hold only 64
connections (--max-connections-per-ip); that limit is tested in
e2e_hardening.py. LOAD_WAITS, LOAD_SLOW and LOAD_SECONDS scale it."""

import os
import re
import resource
import selectors
import shutil
import socket
import subprocess
import threading
import time

import testlib
from testlib import check

testlib.skip_without_egl()

WAITS = int(os.environ.get("LOAD_WAITS", "2000"))
SLOW = int(os.environ.get("LOAD_SLOW", "500"))
SECONDS = float(os.environ.get("LOAD_SECONDS", "0"))
S = testlib.TIME_SCALE  # time bounds stretch under the sanitizers
ADDRESSES = ["127.0.1.%d" % i for i in range(1, 41)]

soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))
check(hard >= WAITS + SLOW + 200, "enough descriptors for the clients (%d)" % hard)


def connect(port, src):
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.bind((src, 0))
    s.connect(("127.0.0.1", port))
    return s


def healthz_once(port):
    t0 = time.perf_counter()
    s = connect(port, "127.0.0.1")
    s.settimeout(5 * S)
    s.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
    data = b""
    while True:
        chunk = s.recv(4096)
        if not chunk:
            break
        data += chunk
    s.close()
    return time.perf_counter() - t0, data.startswith(b"HTTP/1.1 200")


stop = threading.Event()
latencies = []
probe_errors = []


def probe(port):
    while not stop.is_set():
        try:
            took, ok = healthz_once(port)
            latencies.append(took)
            if not ok:
                probe_errors.append("status")
        except OSError as e:
            probe_errors.append(str(e))
        time.sleep(0.02)


slow_cut = [0]


def trickle(port):
    """SLOW clients, each sending one header byte a second; when the daemon
    cuts one (its header deadline), it reconnects at once."""
    sel = selectors.DefaultSelector()
    socks = []
    for i in range(SLOW):
        s = connect(port, ADDRESSES[i % len(ADDRESSES)])
        s.setblocking(False)
        socks.append(s)
    header = b"GET /healthz HTTP/1.1\r\nX-Slow: " + b"a" * 4000
    pos = [0] * SLOW
    while not stop.is_set():
        for i, s in enumerate(socks):
            try:
                s.send(header[pos[i] % len(header):pos[i] % len(header) + 1])
                pos[i] += 1
            except OSError:
                slow_cut[0] += 1
                s.close()
                try:
                    socks[i] = connect(port, ADDRESSES[i % len(ADDRESSES)])
                    socks[i].setblocking(False)
                    pos[i] = 0
                except OSError:
                    pass
        stop.wait(1.0)
    for s in socks:
        s.close()


d = testlib.Daemon()
try:
    job = d.submit({"frames": 1000000, "warmup_frames": 0, "timeout_s": 0, "scene": {"width": 128, "height": 128}})
    deadline = time.time() + 30
    while d.json("GET", "/v1/jobs/" + job)[1].get("status") != "running" and time.time() < deadline:
        time.sleep(0.05)

    # Unloaded baseline for the record.
    base = sorted(healthz_once(d.port)[0] for _ in range(50))

    waits = []
    for i in range(WAITS):
        s = connect(d.port, ADDRESSES[i % len(ADDRESSES)])
        s.sendall(("GET /v1/jobs/%s?wait=3600 HTTP/1.1\r\nHost: x\r\n\r\n" % job).encode())
        waits.append(s)
    load_start = time.time()
    slow_thread = threading.Thread(target=trickle, args=(d.port,))
    slow_thread.start()

    def long_polls():
        _, _, metrics = d.request("GET", "/metrics")
        m = re.search(r"^shadebench_http_long_polls (\d+)", metrics.decode(), re.M)
        return int(m.group(1)) if m else None

    deadline = time.time() + 30 * S
    while long_polls() != WAITS and time.time() < deadline:
        time.sleep(0.1)
    n = long_polls()
    check(n == WAITS, "%d long-polls open (%s)" % (WAITS, n))
    probe_thread = threading.Thread(target=probe, args=(d.port,))
    probe_thread.start()

    # New jobs are accepted while all of that is open.
    accepted = 0
    for _ in range(5):
        status, body = d.json("POST", "/v1/jobs", {"frames": 2, "warmup_frames": 0,
                                                   "scene": {"width": 32, "height": 32}})
        accepted += status == 202
    check(accepted == 5, "new jobs accepted under load (%d of 5)" % accepted)

    # wrk on the GET endpoints, zero errors.
    wrk = shutil.which("wrk")
    check(wrk is not None, "wrk is installed (Debian package wrk)")
    if wrk:
        for path in ("/healthz", "/v1/info", "/v1/jobs/" + job, "/metrics"):
            out = subprocess.run([wrk, "-t1", "-c8", "-d1s", "--timeout", "5s", d.base + path],
                                 capture_output=True, text=True)
            reqs = re.search(r"(\d+) requests in", out.stdout)
            errors = re.search(r"Socket errors: (.*)", out.stdout)
            non2xx = re.search(r"Non-2xx or 3xx responses: (\d+)", out.stdout)
            print("wrk %s: %s requests, socket errors: %s, non-2xx: %s" %
                  (path, reqs and reqs.group(1), errors and errors.group(1),
                   non2xx and non2xx.group(1)))
            check(out.returncode == 0 and reqs and int(reqs.group(1)) > 0 and not errors and
                  not non2xx, "wrk %s: no error" % path)

    # Until every slow client was cut at its header deadline (the event the
    # load waits for), and at least LOAD_SECONDS.
    deadline = load_start + 40 * S
    while ((slow_cut[0] < SLOW or time.time() < load_start + SECONDS) and
           time.time() < deadline):
        time.sleep(0.1)
    stop.set()
    probe_thread.join()
    slow_thread.join()
    lat = sorted(latencies)
    p99 = lat[int(len(lat) * 0.99) - 1] if lat else float("inf")
    print("/healthz under load: %d probes, median %.1f ms, p99 %.1f ms, max %.1f ms "
          "(unloaded: median %.1f ms); slow clients cut %d times" %
          (len(lat), lat[len(lat) // 2] * 1e3 if lat else -1, p99 * 1e3, lat[-1] * 1e3 if lat else -1,
           base[len(base) // 2] * 1e3, slow_cut[0]))
    check(len(lat) >= 100 and not probe_errors,
          "healthz always answered (%d probes, errors %s)" % (len(lat), probe_errors[:3]))
    check(p99 <= 0.100 * S, "healthz p99 within 100 ms under load (%.1f ms)" % (p99 * 1e3))
    check(slow_cut[0] >= SLOW, "the slow clients were cut at their header deadline (%d)" % slow_cut[0])
    status, body = d.json("GET", "/v1/jobs/" + job)
    check(body.get("status") == "running" and body["progress"]["frames_done"] > 0,
          "the job kept rendering")

    # SIGTERM with every wait open: each is answered and the daemon exits.
    t0 = time.time()
    d.proc.send_signal(15)
    d.proc.wait(60 * S)
    took = time.time() - t0
    answered = 0
    for s in waits:
        s.settimeout(5)
        try:
            answered += s.recv(64).startswith(b"HTTP/1.1 503")
        except OSError:
            pass
        s.close()
    print("SIGTERM with %d waits open: exit after %.2f s, %d answered 503" % (WAITS, took, answered))
    check(took < 5 * S, "SIGTERM exits within 5 s (%.2f s)" % took)
    check(answered == WAITS, "every wait answered 503 (%d of %d)" % (answered, WAITS))
finally:
    stop.set()
    testlib.stop_and_check(d)
testlib.finish("e2e_load")
