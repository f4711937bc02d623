#!/usr/bin/env python3
"""The record store at scale: a real shadebenchd on a temporary state
directory holding --jobs finished jobs (100,000 by default), measured
against the goals of issue #20: start-up to /healthz and to the first list,
RSS after start and after listing, and p50/p99 of a page of 100 (cursors
deep into the list included), of a label filter and of one job, over
--requests requests each. Also the cost of a submission (a durable commit).

  SHADEBENCHD=build/shadebenchd bench/bench_store.py [--jobs 100000] [--requests 200]

The store is filled in its own format without the daemon's help: one real
job runs first, and its row (spec, figures, labels) is copied --jobs times
into store.db with Python's sqlite3 module, under time-ordered ids and
finish times, with labels commit=cNNNNN (10 jobs each) and branch=main or
topic, and techniques in turn; each job gets its directory (the start-up
scan reads them), and --with-results of them the real job's result.json.
Retention is off (--keep-jobs 0 --keep-days 0) so that all of them stay.

With --old-daemon PATH (a build from before the store) and --legacy N, it
also writes N jobs in the old format (job.json, spec.json, result.json per
directory) and measures the old daemon's start and RSS on them, then the
new one's first start (the import) and second start on the same directory."""

import argparse
import http.client
import json
import os
import random
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--jobs", type=int, default=100000)
ap.add_argument("--requests", type=int, default=200)
ap.add_argument("--with-results", type=int, default=200,
                help="jobs that get a result.json, for GET /v1/jobs/ID")
ap.add_argument("--submissions", type=int, default=100)
ap.add_argument("--old-daemon", help="a shadebenchd from before the store, for --legacy")
ap.add_argument("--legacy", type=int, default=0, help="jobs in the old format (with --old-daemon)")
ap.add_argument("--keep", action="store_true", help="keep the temporary state directory")
args = ap.parse_args()

SHADEBENCHD = os.environ.get("SHADEBENCHD", "./shadebenchd")
GOALS = {"start_s": 2.0, "rss_mb": 200.0, "p99_ms": 50.0}
TINY = {"technique": "unlit", "frames": 1, "warmup_frames": 0, "scene": {"width": 32, "height": 32},
        "labels": {"commit": "c00000", "branch": "main"}}
tmp = tempfile.mkdtemp(prefix="bench-store-")


class Daemon:
    def __init__(self, binary, state, *extra):
        self.port_file = os.path.join(tmp, "port")
        if os.path.exists(self.port_file):
            os.remove(self.port_file)
        self.log = open(os.path.join(tmp, "daemon.log"), "a")
        self.t0 = time.monotonic()
        self.proc = subprocess.Popen([binary, "--listen", "127.0.0.1:0", "--port-file", self.port_file,
                                      "--state-dir", state] + list(extra),
                                     stdout=self.log, stderr=subprocess.STDOUT)
        while not os.path.exists(self.port_file):
            if self.proc.poll() is not None:
                sys.exit("the daemon did not start: see %s" % self.log.name)
            time.sleep(0.002)
        with open(self.port_file) as f:
            self.port = int(f.read())
        self.conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=600)

    def get(self, path, body=None, method="GET"):
        t = time.monotonic()
        self.conn.request(method, path, body=json.dumps(body) if body is not None else None)
        r = self.conn.getresponse()
        data = r.read()
        return r.status, data, (time.monotonic() - t) * 1000.0

    def wait_healthy(self):
        while True:
            try:
                if self.get("/healthz")[0] == 200:
                    return time.monotonic() - self.t0
            except OSError:
                self.conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=600)
            time.sleep(0.002)

    def memory(self):
        out = {}
        with open("/proc/%d/status" % self.proc.pid) as f:
            for line in f:
                if line.startswith(("VmRSS:", "VmHWM:")):
                    out[line.split(":")[0]] = int(line.split()[1]) / 1024.0
        return out

    def cpu_s(self):
        with open("/proc/%d/stat" % self.proc.pid) as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    def stop(self):
        self.conn.close()
        self.proc.send_signal(signal.SIGTERM)
        self.proc.wait()
        self.log.close()


def pct(values, p):
    s = sorted(values)
    return s[min(len(s) - 1, int(round(p / 100.0 * (len(s) - 1))))]


def line(name, values, goal=None):
    p50, p99 = statistics.median(values), pct(values, 99)
    verdict = "" if goal is None else ("  goal <= %g ms at p99: %s" % (goal, "met" if p99 <= goal else "MISSED"))
    print("  %-44s p50 %7.2f ms  p99 %7.2f ms  (%d requests)%s" % (name, p50, p99, len(values), verdict))


sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchrun  # noqa: E402
import storefill  # noqa: E402
from storefill import stamp_id  # noqa: E402
bench = benchrun.Run()
bench.start()


def uptime_load():
    with open("/proc/loadavg") as f:
        return f.read().split()[0]


# 1. One real job: the template of every row, and the store's schema.
state = os.path.join(tmp, "state")
d = Daemon(SHADEBENCHD, state, "--keep-jobs", "0", "--keep-days", "0")
d.wait_healthy()
status, body, _ = d.get("/v1/jobs", TINY, "POST")
template_id = json.loads(body)["id"]
while json.loads(d.get("/v1/jobs/%s?wait=60" % template_id)[1])["status"] in ("queued", "running"):
    pass
d.stop()
t_fill = time.monotonic()
filled = storefill.fill(state, template_id, args.jobs, args.with_results)
ids, start, spec_template = filled["ids"], filled["start"], filled["spec"]
result_text, with_result, db_mb = filled["result_text"], filled["with_result"], filled["db_mb"]
rng = random.Random(21)
print("filled %d finished jobs in %.1f s: store.db %.1f MB, %d job directories (%d with result.json)"
      % (args.jobs, time.monotonic() - t_fill, db_mb, args.jobs, len(with_result)))

# 3. The measurements.
print("load average before: %s (%d CPUs)" % (uptime_load(), os.cpu_count()))
d = Daemon(SHADEBENCHD, state, "--keep-jobs", "0", "--keep-days", "0", "--queue-size", "10000")
start_s = d.wait_healthy()
status, body, first_ms = d.get("/v1/jobs?limit=100")
first_s = time.monotonic() - d.t0
check = json.loads(body)
assert status == 200 and len(check["jobs"]) == 100 and check.get("next"), (status, body[:200])
mem_start = d.memory()
cpu_start = d.cpu_s()

pages, deep, label_one, label_wide, single = [], [], [], [], []
for _ in range(args.requests):
    k = rng.randrange(args.jobs)
    s, body, ms = d.get("/v1/jobs?limit=100&cursor=%s" % ids[k])
    assert s == 200 and len(json.loads(body)["jobs"]) == min(100, args.jobs - k - 1), s
    pages.append(ms)
for _ in range(args.requests):
    k = rng.randrange(args.jobs)
    s, body, ms = d.get("/v1/jobs?label.commit=c%05d&limit=100" % (k // 10))
    assert s == 200 and len(json.loads(body)["jobs"]) == min(10, args.jobs - (k // 10) * 10), s
    label_one.append(ms)
for _ in range(args.requests):
    k = rng.randrange(args.jobs)
    s, body, ms = d.get("/v1/jobs?label.branch=topic&technique=osl&limit=100&cursor=%s" % ids[k])
    assert s == 200, s
    label_wide.append(ms)
for _ in range(args.requests):
    # The deepest pages: the last 1% of the list.
    k = args.jobs - 1 - rng.randrange(max(1, args.jobs // 100))
    s, body, ms = d.get("/v1/jobs?limit=100&cursor=%s" % ids[k])
    assert s == 200, s
    deep.append(ms)
for i in range(args.requests):
    k = sorted(with_result)[i % len(with_result)]
    s, body, ms = d.get("/v1/jobs/%s" % ids[k])
    assert s == 200 and b'"result"' in body, s
    single.append(ms)
mem_list = d.memory()
cpu_list = d.cpu_s() - cpu_start

submits = []
for _ in range(args.submissions):
    s, body, ms = d.get("/v1/jobs", TINY, "POST")
    assert s == 202, (s, body)
    submits.append(ms)
cpu_all = d.cpu_s()
d.stop()

print("\nshadebenchd %s with %d finished jobs (store.db %.1f MB), load average now %s"
      % (SHADEBENCHD, args.jobs, db_mb, uptime_load()))
print("  start to /healthz 200        %6.2f s   goal <= %g s: %s"
      % (start_s, GOALS["start_s"], "met" if start_s <= GOALS["start_s"] else "MISSED"))
print("  start to the first list      %6.2f s   (that list %.1f ms)" % (first_s, first_ms))
print("  RSS after start              %6.1f MB  (peak %.1f MB)  goal <= %g MB: %s"
      % (mem_start["VmRSS"], mem_start["VmHWM"], GOALS["rss_mb"],
         "met" if mem_start["VmHWM"] <= GOALS["rss_mb"] else "MISSED"))
print("  RSS after %d reads         %6.1f MB  (peak %.1f MB)  goal <= %g MB: %s"
      % (4 * args.requests + args.requests, mem_list["VmRSS"], mem_list["VmHWM"], GOALS["rss_mb"],
         "met" if mem_list["VmHWM"] <= GOALS["rss_mb"] else "MISSED"))
line("page of 100 at a random cursor", pages, GOALS["p99_ms"])
line("page of 100 in the last 1%", deep, GOALS["p99_ms"])
line("label filter (label.commit=, 10 jobs)", label_one, GOALS["p99_ms"])
line("label.branch=topic&technique=osl, cursor", label_wide, GOALS["p99_ms"])
line("one job (GET /v1/jobs/ID, result.json)", single)
line("submission (POST, a durable commit)", submits)
print("  daemon CPU: %.2f s for the %d reads, %.2f s in all (start, reads, %d submissions and their jobs)"
      % (cpu_list, 5 * args.requests, cpu_all, args.submissions))

# 4. The old daemon, on the same number of jobs in its own format.
if args.old_daemon and args.legacy:
    legacy = os.path.join(tmp, "legacy")
    os.makedirs(os.path.join(legacy, "jobs"))
    t_fill = time.monotonic()
    spec_text = json.dumps(spec_template)
    for i in range(args.legacy):
        created = start + i * 5.0
        job_id = stamp_id(created, i)
        dirp = os.path.join(legacy, "jobs", job_id)
        os.mkdir(dirp)
        lab = {"commit": "c%05d" % (i // 10), "branch": "main" if i % 3 else "topic"}
        spec = dict(spec_template, labels=lab)
        job = {"id": job_id, "status": "done", "technique": spec["technique"],
               "progress": {"frames_done": 1, "frames_total": 1},
               "created": None, "started": None, "finished": None, "spec": spec,
               "times_unix": [created, created + 1, created + 2]}
        with open(os.path.join(dirp, "job.json"), "w") as f:
            json.dump(job, f)
        with open(os.path.join(dirp, "spec.json"), "w") as f:
            json.dump({"id": job_id, "created_unix": created, "spec": spec}, f)
        with open(os.path.join(dirp, "result.json"), "w") as f:
            f.write(result_text)
    print("\nwrote %d jobs in the old format in %.1f s" % (args.legacy, time.monotonic() - t_fill))
    runs = [("old daemon %s" % args.old_daemon, args.old_daemon),
            ("new daemon, first start: imports them", SHADEBENCHD),
            ("new daemon, second start", SHADEBENCHD)]
    for k, (name, binary) in enumerate(runs):
        d = Daemon(binary, legacy, "--keep-jobs", "0", "--keep-days", "0", "--queue-size", "10000")
        start_s = d.wait_healthy()
        mem_start = d.memory()
        s, body, list_ms = d.get("/v1/jobs")
        mem_list = d.memory()
        cpu = d.cpu_s()
        print("  %-40s start %6.2f s, RSS %6.1f MB (peak %.1f), GET /v1/jobs %7.1f ms (%d KB), "
              "then RSS %.1f MB, CPU %.1f s"
              % (name, start_s, mem_start["VmRSS"], mem_start["VmHWM"], list_ms, len(body) // 1024,
                 mem_list["VmRSS"], cpu))
        if k != 1:  # the old format's submissions, and the store's on the same directory
            submits = [d.get("/v1/jobs", TINY, "POST")[2] for _ in range(args.submissions)]
            line("submission (POST) with %d jobs there" % args.legacy, submits)
        d.stop()

if args.keep:
    print("state kept in", tmp)
else:
    shutil.rmtree(tmp)
bench.end([])
