"""The record store end to end. Lists come in pages: following "next" walks
every job exactly once, in submission order, with filters kept and a job
submitted meanwhile coming at the end; a bad limit or cursor gets 400 naming
it; the sweep list pages too; the client's history and list follow next to
the end. Retention keeps a running sweep's point jobs. kill -9 in the middle of a stream of submissions loses no job that
was answered 202. A state directory of the earlier version (job.json and
sweep.json files, tests/e2e/fixtures/legacy-state, made by
make_legacy_state.py with that version) is imported on first start:
results, images, labels, the sweep's table and the job SIGTERM had stopped
all come back, and the next start has nothing left to import."""

import json
import os
import shutil
import signal
import tempfile
import threading
import time
import urllib.parse

import storelib
import testlib
from clientlib import Client
from testlib import check

testlib.skip_without_egl()
TINY = {"technique": "unlit", "frames": 1, "warmup_frames": 0, "scene": {"width": 32, "height": 32}}
FIXTURE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fixtures", "legacy-state")


def without_urls(value):
    """What is stored, without the URLs the API adds as it serves it."""
    if isinstance(value, dict):
        return {k: without_urls(v) for k, v in value.items() if k != "url" and not k.endswith("_url")}
    if isinstance(value, list):
        return [without_urls(v) for v in value]
    return value


def walk(d, path):
    """Follows next from path; returns (ids in order, pages, the next links)."""
    ids, pages, links = [], 0, []
    while path and pages < 100:
        status, body = d.json("GET", path)
        if not check(status == 200, "GET %s: %d %s" % (path, status, body)):
            break
        ids += [j["id"] for j in body.get("jobs", body.get("sweeps", []))]
        pages += 1
        path = body.get("next")
        if path:
            links.append(path)
    return ids, pages, links


# --- Pages ------------------------------------------------------------------
d = testlib.Daemon()
cl = Client(d)
try:
    made = []
    for i in range(7):
        job = dict(TINY, technique="unlit" if i % 3 else "forward", labels={"commit": "a" if i % 2 else "b"})
        made.append((d.submit(job), job))
    for job_id, _ in made:
        check(d.wait(job_id)["status"] == "done", "job %s done" % job_id)
    all_ids = [job_id for job_id, _ in made]

    ids, pages, links = walk(d, "/v1/jobs?limit=3")
    check(ids == all_ids and pages == 3, "limit=3: every job once, in order, in 3 pages: %s in %d" % (ids, pages))
    check(all(link.startswith("/v1/jobs?") and "cursor=" in link and "limit=3" in link for link in links),
          "next links name the list, the limit and a cursor: %s" % links)
    status, body = d.json("GET", "/v1/jobs")
    check(status == 200 and [j["id"] for j in body["jobs"]] == all_ids and "next" not in body,
          "no limit: one page of up to 100, no next")
    status, body = d.json("GET", "/v1/jobs?limit=7")
    check("next" not in body and len(body["jobs"]) == 7, "a page that ends the list has no next")

    want_a = [job_id for job_id, job in made if job["labels"]["commit"] == "a"]
    ids, pages, links = walk(d, "/v1/jobs?label.commit=a&limit=2")
    check(ids == want_a and pages == 2, "a label filter, paged: %s in %d pages" % (ids, pages))
    check(all("label.commit=a" in link for link in links), "the filter stays in next: %s" % links)
    want = [job_id for job_id, job in made if job["technique"] == "unlit" and job["labels"]["commit"] == "b"]
    ids, _, _ = walk(d, "/v1/jobs?technique=unlit&status=done&label.commit=b&limit=1")
    check(ids == want, "filters combine with pages: %s" % ids)
    since = d.json("GET", "/v1/jobs/" + all_ids[4])[1]["created"]
    ids, _, links = walk(d, "/v1/jobs?" + urllib.parse.urlencode({"since": since, "limit": 2}))
    check(ids == all_ids[4:] and all("since=" in link for link in links),
          "since, paged: %s, %s" % (ids, links))

    # The cursor is a position: a job submitted meanwhile comes at the end.
    status, first = d.json("GET", "/v1/jobs?limit=4")
    late = d.submit(TINY)
    ids = [j["id"] for j in first["jobs"]] + walk(d, first["next"])[0]
    check(ids == all_ids + [late], "a job submitted between pages comes last, nothing twice: %s" % ids)
    d.wait(late)

    for query, field in (("limit=0", "limit"), ("limit=1001", "limit"), ("limit=ten", "limit"),
                         ("limit=", "limit"), ("cursor=../etc", "cursor"), ("cursor=", "cursor"),
                         ("technique=unlit&cursor=x", "cursor")):
        status, body = d.json("GET", "/v1/jobs?" + query)
        check(status == 400 and body.get("error", {}).get("field") == field
              and len(body["error"].get("message", "")) > 10,
              "?%s -> 400 naming %s: %d %s" % (query, field, status, body))
    for query, field in (("limit=0", "limit"), ("cursor=..", "cursor"), ("technique=unlit", "technique")):
        status, body = d.json("GET", "/v1/sweeps?" + query)
        check(status == 400 and body.get("error", {}).get("field") == field,
              "sweeps ?%s -> 400 naming %s: %d %s" % (query, field, status, body))

    sweeps = []
    for lights in (1, 2):
        status, reply = d.json("POST", "/v1/sweeps", {"base": TINY, "vary": {"scene.lights": [lights]},
                                                     "time_reference": False})
        sweeps.append(reply.get("id"))
    for sweep_id in sweeps:
        check(d.wait_sweep(sweep_id)["status"] == "done", "sweep %s done" % sweep_id)
    ids, pages, _ = walk(d, "/v1/sweeps?limit=1")
    check(ids == sweeps and pages == 2, "the sweep list pages too: %s in %d" % (ids, pages))

    # The client follows next to the end.
    out = cl.run("history", "--filter", "limit=2", "--filter", "label.commit=a")
    rows = [line.split()[0] for line in out.stdout.splitlines()[1:] if line.strip()]
    check(out.returncode == 0 and rows == want_a, "history reads every page: %s (%s)" % (rows, out.stderr[-200:]))
    out = cl.run("list")
    listed = [line.split()[0] for line in out.stdout.splitlines() if line.strip()]
    check(out.returncode == 0 and all_ids + [late] == [i for i in listed if i in all_ids + [late]]
          and len(listed) == len(all_ids) + 1 + 2,  # and the sweeps' point jobs
          "list reads every page: %d jobs" % len(listed))
finally:
    testlib.stop_and_check(d)

# --- Retention keeps what a running sweep needs -------------------------------
d = testlib.Daemon("--keep-jobs", "1")
try:
    # The third point renders long enough to be seen running: the render
    # thread starts it only once the second point's finish (and the
    # retention pass that follows it) has returned, so the first two point
    # jobs are checked after retention had its chance at them. 600 frames
    # of coarse spheres (64 triangles, not the grid's 1,024): a second or
    # more (2 to 6 ms a frame at load 8; 400 of the full grid took 19 s).
    coarse = dict(TINY, scene=dict(TINY["scene"], sphere_segments=8))
    status, reply = d.json("POST", "/v1/sweeps", {"base": coarse, "vary": {"frames": [1, 1, 600]},
                                                 "time_reference": False})
    seen, deadline = None, time.time() + 60 * testlib.TIME_SCALE
    while time.time() < deadline:
        sweep = d.json("GET", "/v1/sweeps/" + reply["id"])[1]
        rows = [p["job"] for p in sweep.get("points", [])]
        current = sweep.get("current_job")
        if len(rows) == 2 and current:
            job = d.json("GET", "/v1/jobs/" + current)[1]
            if job.get("status") == "running" and job.get("progress", {}).get("frames_done", 0) > 0:
                seen = rows
                break
        if sweep.get("status") not in ("queued", "running"):
            break
        time.sleep(0.02)
    check(seen is not None and all(d.json("GET", "/v1/jobs/" + job_id)[0] == 200 for job_id in seen),
          "its finished point jobs stay while it runs, though only 1 finished job is kept: %s" % seen)
    sweep = d.wait_sweep(reply["id"])
    points = [p["job"] for p in sweep.get("points", [])]
    check(sweep["status"] == "done" and len(points) == 3, "a sweep of 3 points under --keep-jobs 1")
    last = d.run(TINY)
    deadline = time.time() + 10
    jobs_dir = os.path.join(d.state, "jobs")
    while time.time() < deadline and (len(storelib.ids(d.state)) > 1 or len(os.listdir(jobs_dir)) > 1):
        time.sleep(0.05)
    check(storelib.ids(d.state) == [last["id"]] and os.listdir(jobs_dir) == [last["id"]],
          "once it is done, retention removes them, rows and directories: %s, %s"
          % (storelib.ids(d.state), os.listdir(jobs_dir)))
    check(d.json("GET", "/v1/sweeps/" + reply["id"])[0] == 200, "the sweep, the newest finished one, stays")
finally:
    testlib.stop_and_check(d)

# --- kill -9 in a stream of submissions -------------------------------------
d = testlib.Daemon("--queue-size", "10000")
state = d.state
# Five jobs done first, while nothing else runs: their results must come back
# unchanged. (Waited for in the middle of the stream, they took 4.5 s under
# the sanitizers, while the four threads queued jobs the test then read one
# by one, listed and deleted: 1,133 of them in the plain build.)
done_before = {}
for job_id in [d.submit(TINY) for _ in range(5)]:
    job = d.wait(job_id)
    if job.get("status") == "done":
        done_before[job_id] = job["result"]
accepted, lock, stop = list(done_before), threading.Lock(), threading.Event()


def submitter():
    while not stop.is_set():
        try:
            status, body = d.json("POST", "/v1/jobs", TINY, timeout=10)
        except OSError:
            return  # the daemon is gone
        if status == 202:
            with lock:
                accepted.append(body["id"])


threads = [threading.Thread(target=submitter) for _ in range(4)]
for t in threads:
    t.start()
deadline = time.time() + 30 * testlib.TIME_SCALE
while time.time() < deadline:
    with lock:
        if len(accepted) >= 40 + len(done_before):
            break
    time.sleep(0.01)
d.proc.send_signal(signal.SIGKILL)  # with submissions still in flight
d.proc.wait()
stop.set()
for t in threads:
    t.join()
d.log.close()
print("kill -9 after %d jobs were accepted" % len(accepted))
check(len(accepted) >= 40 + len(done_before) and len(done_before) == 5,
      "%d jobs accepted, %d seen done, before kill -9" % (len(accepted), len(done_before)))
again = testlib.Daemon("--state-dir", state, "--queue-size", "10000")
try:
    missing = [job_id for job_id in accepted if again.json("GET", "/v1/jobs/" + job_id)[0] != 200]
    check(not missing, "every job answered 202 is there after kill -9: %d of %d missing %s"
          % (len(missing), len(accepted), missing[:5]))
    check(all(again.json("GET", "/v1/jobs/" + job_id)[1].get("result") == result
              for job_id, result in done_before.items()), "finished ones are finished, results unchanged")
    listed, _, _ = walk(again, "/v1/jobs?limit=1000")
    check(set(accepted) <= set(listed), "and listed")
finally:
    testlib.stop_and_check(again)
d.cleanup(keep=testlib.failures > 0)

# --- A state directory of the earlier version -----------------------------
old = {}
for name in sorted(os.listdir(os.path.join(FIXTURE, "jobs"))):
    with open(os.path.join(FIXTURE, "jobs", name, "job.json")) as f:
        old[name] = json.load(f)
sweep_id = os.listdir(os.path.join(FIXTURE, "sweeps"))[0]
with open(os.path.join(FIXTURE, "sweeps", sweep_id, "sweep.json")) as f:
    old_sweep = json.load(f)
stopped = [i for i, j in old.items() if j["status"] == "queued"]
legacy = tempfile.mkdtemp(prefix="shadebench-legacy-")
legacy_state = os.path.join(legacy, "state")
shutil.copytree(FIXTURE, legacy_state)
d = testlib.Daemon("--state-dir", legacy_state)
try:
    log = open(d.log_path).read()
    check("imported %d job(s)" % len(old) in log and "imported 1 sweep(s)" in log,
          "the import is logged: %s" % [line for line in log.splitlines() if "import" in line])
    ids, _, _ = walk(d, "/v1/jobs?limit=4")
    check(ids == sorted(old), "every old job is listed, in order: %s" % ids)
    for job_id, was in old.items():
        status, job = d.json("GET", "/v1/jobs/" + job_id)
        if was["status"] in ("done", "cancelled"):
            check(status == 200 and job["status"] == was["status"] and job["spec"] == was["spec"]
                  and job["created"] == was["created"] and job["finished"] == was["finished"],
                  "%s: %s as before" % (job_id, was["status"]))
        if was["status"] == "done":
            with open(os.path.join(FIXTURE, "jobs", job_id, "result.json")) as f:
                check(without_urls(job.get("result")) == json.load(f),
                      "%s: its result is served as before" % job_id)
    labelled = [i for i, j in old.items() if j["spec"].get("labels", {}).get("commit") == "old1"]
    status, body = d.json("GET", "/v1/jobs?label.commit=old1")
    check([j["id"] for j in body["jobs"]] == labelled and body["jobs"][0].get("figures", {}).get("frame_ms"),
          "labels and figures of old jobs: %s" % body)
    png = os.path.join(d.tmp, "f.png")
    check(d.download("/v1/jobs/%s/frames/2.png" % labelled[0], png) == 200 and
          open(png, "rb").read() == open(os.path.join(FIXTURE, "jobs", labelled[0], "frame-000002.png"), "rb").read(),
          "and their images")
    status, sweep = d.json("GET", "/v1/sweeps/" + sweep_id)
    check(status == 200 and sweep["status"] == old_sweep["status"]
          and without_urls(sweep["points"]) == old_sweep["points"]
          and sweep.get("result") == old_sweep.get("result") and sweep["spec"] == old_sweep["spec"],
          "the sweep is served as before, its table whole")
    # The job SIGTERM stopped runs again, first; the one behind it waits.
    deadline = time.time() + 30
    while d.json("GET", "/v1/jobs/" + stopped[0])[1]["status"] != "running" and time.time() < deadline:
        time.sleep(0.05)
    check(d.json("GET", "/v1/jobs/" + stopped[0])[1]["status"] == "running",
          "the job SIGTERM stopped runs again")
    d.json("DELETE", "/v1/jobs/" + stopped[0])
    check(d.wait(stopped[1])["status"] == "done", "and the one queued behind it runs next")
    state = legacy_state
    check(os.path.exists(storelib.db_path(state)), "store.db is made")
    left = [p for p in (os.path.join(r, f) for r, _, fs in os.walk(state) for f in fs)
            if p.endswith(("/job.json", "/sweep.json"))]
    check(not left, "job.json and sweep.json are gone, their rows stored: %s" % left)
    check(os.path.exists(os.path.join(state, "sweeps", sweep_id, "spec.json")), "a sweep keeps its spec.json")
    check(not os.path.exists(os.path.join(state, "quarantine")), "nothing needed quarantine")
finally:
    testlib.stop_and_check(d)
again = testlib.Daemon("--state-dir", legacy_state)
try:
    check("imported" not in open(again.log_path).read(), "the next start has nothing to import")
    ids, _, _ = walk(again, "/v1/jobs?limit=1000")
    check(ids[:len(old)] == sorted(old) and
          without_urls(again.json("GET", "/v1/sweeps/" + sweep_id)[1].get("points")) == old_sweep["points"],
          "and serves the same")
finally:
    testlib.stop_and_check(again)
if not testlib.failures:
    shutil.rmtree(legacy, ignore_errors=True)
testlib.finish("e2e_store")
