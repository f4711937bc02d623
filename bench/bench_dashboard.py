#!/usr/bin/env python3
"""The dashboard with the store full: a real shadebenchd holding --jobs
finished jobs (100,000 by default; bench/storefill.py fills the store in
its own format from one real job), and headless Chromium
(tests/e2e/browserlib.py) loading the job list's first page (#/jobs: the
newest 50 jobs, newest first) and a job's page (#/job/ID: its figures,
frame-time charts and its capture compared with its reference), --loads
times each, in turn. A load is timed from the navigation to the page
drawn: the router done, and for the job page the two images on their
canvases and the frame-time chart made. Also the API requests those pages
make, timed alone. Prints medians and maxima; the goal is well under a
second for each page.

  SHADEBENCHD=build/shadebenchd bench/bench_dashboard.py [--jobs 100000] [--loads 20]"""

import http.client
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchrun  # noqa: E402
import storefill  # noqa: E402
import browserlib  # noqa: E402  (benchrun puts tests/e2e on the path)

ap = benchrun.parser()
ap.add_argument("--jobs", type=int, default=100000)
ap.add_argument("--loads", type=int, default=20)
ap.add_argument("--json", help="write the figures here")
args = ap.parse_args()
SHADEBENCHD = os.environ.get("SHADEBENCHD", "./shadebenchd")
GOAL_MS = 1000.0
# The template: a job with a reference, so that its page compares a capture.
TEMPLATE = {"technique": "osl", "frames": 30, "warmup_frames": 2, "capture_interval": 30,
            "osl": {"resolution": "auto"}, "reference": "forward",
            "scene": {"width": 320, "height": 200, "sphere_segments": 8},
            "labels": {"commit": "c00000", "branch": "main"}}

bench = benchrun.Run()
bench.start()
tmp = tempfile.mkdtemp(prefix="bench-dashboard-")
state = os.path.join(tmp, "state")


def start_daemon():
    port_file = os.path.join(tmp, "port")
    if os.path.exists(port_file):
        os.remove(port_file)
    log = open(os.path.join(tmp, "daemon.log"), "a")
    proc = subprocess.Popen([SHADEBENCHD, "--listen", "127.0.0.1:0", "--port-file", port_file, "--state-dir",
                             state, "--keep-jobs", "0", "--keep-days", "0"], stdout=log, stderr=subprocess.STDOUT)
    while not os.path.exists(port_file):
        if proc.poll() is not None:
            sys.exit("the daemon did not start: see %s" % log.name)
        time.sleep(0.01)
    time.sleep(0.05)
    with open(port_file) as f:
        return proc, int(f.read())


def get(port, path, body=None, method="GET"):
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=600)
    t = time.monotonic()
    c.request(method, path, body=json.dumps(body) if body is not None else None)
    r = c.getresponse()
    data = r.read()
    c.close()
    return r.status, data, (time.monotonic() - t) * 1000.0


# 1. One real job, then the fill.
proc, port = start_daemon()
template_id = json.loads(get(port, "/v1/jobs", TEMPLATE, "POST")[1])["id"]
while json.loads(get(port, "/v1/jobs/%s?wait=60" % template_id)[1])["status"] in ("queued", "running"):
    pass
proc.terminate()
proc.wait()
t_fill = time.monotonic()
filled = storefill.fill(state, template_id, args.jobs, min(args.jobs, 200), whole_dirs=True)
print("filled %d finished jobs in %.1f s: store.db %.1f MB" % (args.jobs, time.monotonic() - t_fill, filled["db_mb"]))
# The job page's job: the newest with its files (captures, maps, timings).
job_id = filled["ids"][max(filled["with_result"])]

# 2. The loads, in turn.
proc, port = start_daemon()
while get(port, "/healthz")[0] != 200:
    time.sleep(0.05)
base = "http://127.0.0.1:%d" % port
b = browserlib.Browser(width=1300, height=1000)
pages = {"jobs": [], "job": [], "floor": [], "jobs_in_app": [], "job_in_app": []}
api = {"GET /v1/jobs?order=newest&limit=50": [], "GET /v1/jobs/ID": [], "GET /v1/jobs/ID/timings.csv": [],
       "GET /v1/jobs/ID/frames/K.png": []}
DRAWN = {"jobs": "document.body.dataset.ready === location.hash && "
                 "document.querySelectorAll('#job-list tbody tr').length === 50",
         "job": "document.body.dataset.ready === location.hash && "
                "document.querySelectorAll('.imgcmp canvas.view').length === 2 && "
                "!!(document.querySelector('.frame-times') && document.querySelector('.frame-times').dygraph)"}
job = json.loads(get(port, "/v1/jobs/" + job_id)[1])
frame_url = job["result"]["captures"][0]["url"]
try:
    for k in range(args.loads + 1):  # the first load of each warms the caches: not counted
        # The browser's own floor: a plain text page of the daemon's.
        b.goto("about:blank")
        b.wait("location.href === 'about:blank'", 30)
        t = time.monotonic()
        b.goto(base + "/ui/vendor/LICENSES.txt")
        b.wait("document.readyState === 'complete' && document.body && document.body.textContent.length > 100", 60)
        if k:
            pages["floor"].append((time.monotonic() - t) * 1000.0)
        for name, url in (("jobs", base + "/#/jobs"), ("job", base + "/#/job/" + job_id)):
            b.goto("about:blank")
            b.wait("location.href === 'about:blank'", 30)
            t = time.monotonic()
            b.goto(url)
            b.wait(DRAWN[name], 60, name)
            if k:
                pages[name].append((time.monotonic() - t) * 1000.0)
        # Within the dashboard: a link followed, the page already loaded.
        for name, hash_ in (("jobs_in_app", "#/jobs"), ("job_in_app", "#/job/" + job_id)):
            t = time.monotonic()
            b.eval("location.hash = %s" % json.dumps(hash_))
            b.wait(DRAWN[name.replace("_in_app", "")], 60, name)
            if k:
                pages[name].append((time.monotonic() - t) * 1000.0)
        for name, path in (("GET /v1/jobs?order=newest&limit=50", "/v1/jobs?order=newest&limit=50"),
                           ("GET /v1/jobs/ID", "/v1/jobs/" + job_id),
                           ("GET /v1/jobs/ID/timings.csv", "/v1/jobs/%s/timings.csv" % job_id),
                           ("GET /v1/jobs/ID/frames/K.png", frame_url)):
            status, _, ms = get(port, path)
            assert status == 200, (path, status)
            if k:
                api[name].append(ms)
    # The plain text page (the floor) has no icon: Chromium's request for
    # one is its own, not the dashboard's.
    errors = [m for m in b.console if "favicon.ico" not in m]
finally:
    b.close()
    proc.terminate()
    proc.wait()

print("\nthe dashboard on shadebenchd %s with %d finished jobs, %d loads each (Chromium headless, llvmpipe box)"
      % (SHADEBENCHD, args.jobs, args.loads))
out = {"jobs": args.jobs, "loads": args.loads, "pages": {}, "api": {}}
for name, what in (("jobs", "job list, first page (50 newest), loaded"), ("job", "a job's page, loaded"),
                   ("jobs_in_app", "job list, from a link in the dashboard"),
                   ("job_in_app", "a job's page, from a link in the dashboard"),
                   ("floor", "floor: a plain text page of the daemon")):
    v = pages[name]
    med, worst = statistics.median(v), max(v)
    goal = "" if name == "floor" else "   goal < %g ms: %s" % (GOAL_MS, "met" if worst < GOAL_MS else "MISSED")
    print("  %-44s median %7.1f ms  max %7.1f ms%s" % (what, med, worst, goal))
    out["pages"][name] = {"median_ms": med, "max_ms": worst}
for name, v in api.items():
    print("  %-44s median %7.1f ms  max %7.1f ms" % (name, statistics.median(v), max(v)))
    out["api"][name] = {"median_ms": statistics.median(v), "max_ms": max(v)}
if errors:
    print("  console messages: %s" % errors[:5])
benchrun.write_json(args.json, out, indent=1)
bench.end([])
shutil.rmtree(tmp, ignore_errors=True)  # 100,000 directories: minutes under load
