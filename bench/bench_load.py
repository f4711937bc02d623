#!/usr/bin/env python3
"""What HTTP load costs the measurement: the same job's median frame time
with and without 2,000 open long-polls, 500 clients sending their headers a
byte a second and /healthz probed every 20 ms, in one run, interleaved over
--repeat rounds. Also runs wrk on the GET endpoints during a render.

  SHADEBENCHD=build/shadebenchd bench/bench_load.py [--repeat 3] [--frames 200]

Loopback only; the clients come from 40 addresses of 127.0.1.0/24 (one
address may hold 64 connections). Exits 1 when the loaded median moves by
more than --max-change (default 5%)."""

import re
import resource
import shutil
import socket
import statistics
import subprocess
import sys
import threading
import time

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--frames", type=int, default=200)
ap.add_argument("--width", type=int, default=512)
ap.add_argument("--height", type=int, default=384)
ap.add_argument("--waits", type=int, default=2000)
ap.add_argument("--slow", type=int, default=500)
ap.add_argument("--max-change", type=float, default=5.0, help="percent")
args = ap.parse_args()

resource.setrlimit(resource.RLIMIT_NOFILE, (resource.getrlimit(resource.RLIMIT_NOFILE)[1],) * 2)
ADDRESSES = ["127.0.1.%d" % i for i in range(1, 41)]
JOB = {"technique": "forward", "frames": args.frames, "warmup_frames": 10,
       "scene": {"dynamic": True, "width": args.width, "height": args.height}}


def connect(port, src):
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.bind((src, 0))
    s.connect(("127.0.0.1", port))
    return s


class Load:
    """Long-polls on a job that never ends, trickling clients, a probe."""

    def __init__(self, d, wait_on):
        self.d, self.stop, self.lat = d, threading.Event(), []
        self.waits = []
        for i in range(args.waits):
            s = connect(d.port, ADDRESSES[i % len(ADDRESSES)])
            s.sendall(("GET /v1/jobs/%s?wait=3600 HTTP/1.1\r\nHost: x\r\n\r\n" % wait_on).encode())
            self.waits.append(s)
        self.threads = [threading.Thread(target=self.trickle), threading.Thread(target=self.probe)]
        for t in self.threads:
            t.start()

    def trickle(self):
        socks = [connect(self.d.port, ADDRESSES[i % len(ADDRESSES)]) for i in range(args.slow)]
        for s in socks:
            s.setblocking(False)
        while not self.stop.wait(1.0):
            for i, s in enumerate(socks):
                try:
                    s.send(b"G")
                except OSError:
                    s.close()
                    socks[i] = connect(self.d.port, ADDRESSES[i % len(ADDRESSES)])
                    socks[i].setblocking(False)
        for s in socks:
            s.close()

    def probe(self):
        while not self.stop.wait(0.02):
            t0 = time.perf_counter()
            status = self.d.json("GET", "/healthz")[0]
            if status == 200:
                self.lat.append(time.perf_counter() - t0)

    def close(self):
        self.stop.set()
        for t in self.threads:
            t.join()
        for s in self.waits:
            s.close()
        return self.lat


d = testlib.Daemon()
try:
    status, info = d.json("GET", "/v1/info")
    print("device: %s" % info.get("device", {}).get("gl_renderer"))
    unloaded, loaded, p99s = [], [], []
    for r in range(args.repeat):
        job = d.run(JOB)
        unloaded.append(job["result"]["frame_ms"]["median"])
        # The measured job waits behind a blocker while the load builds up
        # (its long-polls wait on the measured job itself), then runs under it.
        blocker = d.submit(dict(JOB, frames=1000000, timeout_s=0))
        while d.json("GET", "/v1/jobs/" + blocker)[1]["status"] != "running":
            time.sleep(0.05)
        measured = d.submit(JOB)
        load = Load(d, measured)
        time.sleep(1.0)
        d.json("DELETE", "/v1/jobs/" + blocker)
        job = d.wait(measured)
        lat = sorted(load.close())
        loaded.append(job["result"]["frame_ms"]["median"])
        p99 = lat[int(len(lat) * 0.99) - 1] * 1e3 if lat else float("nan")
        p99s.append(p99)
        print("round %d: frame_ms median unloaded %.3f, loaded %.3f (healthz p99 %.1f ms over %d probes)"
              % (r + 1, unloaded[-1], loaded[-1], p99, len(lat)))
    u, l = statistics.median(unloaded), statistics.median(loaded)
    change = (l - u) / u * 100
    print("median of medians: unloaded %.3f ms, loaded %.3f ms: %+.2f%% (limit %.1f%%)"
          % (u, l, change, args.max_change))

    wrk = shutil.which("wrk")
    if wrk:
        blocker = d.submit(dict(JOB, frames=1000000, timeout_s=0))
        for path in ("/healthz", "/v1/info", "/v1/jobs", "/v1/jobs/" + blocker, "/metrics"):
            out = subprocess.run([wrk, "-t2", "-c32", "-d5s", d.base + path], capture_output=True,
                                 text=True).stdout
            rate = re.search(r"Requests/sec:\s*([\d.]+)", out)
            errors = re.search(r"Socket errors: (.*)", out)
            non2xx = re.search(r"Non-2xx or 3xx responses: (\d+)", out)
            print("wrk -t2 -c32 -d5s %s during a render: %s req/s, errors: %s" %
                  (path, rate and rate.group(1),
                   ", ".join(x.group(0) for x in (errors, non2xx) if x) or "none"))
        d.json("DELETE", "/v1/jobs/" + blocker)
    else:
        print("wrk not installed (apt-get install wrk)")
finally:
    d.stop()
    d.cleanup()
sys.exit(0 if abs(change) <= args.max_change else 1)
