"""A cancel frees the render thread for any job (issue #34, item 5).

Before, a DELETE answered at once but the render thread kept drawing what
it had submitted: forward with many lights drained for 86 s and /healthz
then answered 503 "stalled"; OSL at 256 texels a tile, visibility "all",
2,048 lights answered "running" and ended 81 s later (a sixteenth of its
first shading was one submission); after SIGTERM such a job came back
"interrupted", not "cancelled". Here, for both:
- the DELETE ends the job cancelled;
- /healthz never answers 503 meanwhile, and names the job draining (or the
  thread idle), never rendering it once it is cancelled;
- a tiny job submitted after it finishes within seconds;
- a job cancelled just before SIGTERM is still cancelled after a restart.
Time bounds scale with SHADEBENCH_TIME_SCALE."""

import threading
import time

import testlib
from testlib import check

testlib.skip_without_egl()
S = testlib.TIME_SCALE

OSL = {"technique": "osl", "frames": 20, "warmup_frames": 1,
       "osl": {"resolution": 256, "visibility": "all"},
       "scene": {"width": 64, "height": 48, "lights": 2048}}
MANY = {"technique": "forward", "frames": 20, "warmup_frames": 1,
        "scene": {"width": 256, "height": 256, "lights": 65536}}
TINY = {"technique": "unlit", "frames": 1, "warmup_frames": 0, "scene": {"width": 32, "height": 32}}


def wait_running(d, job_id):
    deadline = time.time() + 60 * S
    while time.time() < deadline:
        if d.json("GET", "/v1/jobs/" + job_id)[1].get("status") == "running":
            return True
        time.sleep(0.05)
    return False


class HealthWatch(threading.Thread):
    """Polls /healthz until stopped: every answer's code and render state."""

    def __init__(self, d):
        super().__init__(daemon=True)
        self.d, self.seen, self.done = d, [], threading.Event()

    def run(self):
        while not self.done.is_set():
            status, body = self.d.json("GET", "/healthz")
            render = body.get("render") or {}
            self.seen.append((status, render.get("state"), render.get("job"), render.get("phase")))
            time.sleep(0.05)


def cancel_then_tiny(d, job, what):
    job_id = d.submit(job)
    check(wait_running(d, job_id), "%s runs" % what)
    time.sleep(2.0)
    watch = HealthWatch(d)
    watch.start()
    status, answer = d.json("DELETE", "/v1/jobs/" + job_id)
    cancelled_at = time.time()
    done = d.wait(job_id, timeout=120 * S)
    check(done.get("status") == "cancelled",
          "%s: the DELETE ends it cancelled: %s %s" % (what, done.get("status"), done.get("error")))
    t0 = time.time()
    tiny = d.run(TINY)
    took = time.time() - t0
    watch.done.set()
    watch.join()
    print("%s: DELETE answered %s %s; the tiny job after it took %.2f s (%.2f s after the "
          "DELETE); /healthz saw %s" % (what, status, answer.get("status"), took,
                                         time.time() - cancelled_at,
                                         sorted(set((s, st) for s, st, _, _ in watch.seen))))
    check(tiny.get("status") == "done" and took < 15 * S,
          "%s: a tiny job after the cancel finishes within seconds (%.2f s)" % (what, took))
    check(all(s == 200 for s, _, _, _ in watch.seen),
          "%s: /healthz never answered 503 while the thread let go: %s"
          % (what, [x for x in watch.seen if x[0] != 200][:3]))
    after = [x for x in watch.seen if x[2] == job_id]
    check(all(st in ("busy", "draining") for _, st, _, _ in after),
          "%s: /healthz named the job busy or draining, never stalled: %s" % (what, after[-3:]))
    return job_id


d = testlib.Daemon()
try:
    cancel_then_tiny(d, OSL, "OSL, 256 texels a tile, visibility all, 2,048 lights")
    cancel_then_tiny(d, MANY, "forward, 65,536 lights at 256x256")

    # Cancelled, then SIGTERM before anything else: still cancelled after a
    # restart (it came back "interrupted" when the render thread was stuck
    # in a submission at the stop).
    job_id = d.submit(OSL)
    check(wait_running(d, job_id), "the OSL job runs before the stop")
    time.sleep(2.0)
    status, answer = d.json("DELETE", "/v1/jobs/" + job_id, headers={})
    code = d.stop()
    check(code == 0, "SIGTERM after the DELETE exits 0: %s" % code)
finally:
    first = d
    d = first.restarted()
try:
    job = d.json("GET", "/v1/jobs/" + job_id)[1]
    check(job.get("status") == "cancelled",
          "a job cancelled before a stop is still cancelled after the restart: %s (%s)"
          % (job.get("status"), job.get("error")))
finally:
    testlib.stop_and_check(d)
    first.cleanup(keep=testlib.failures > 0)
testlib.finish("e2e_cancel_drain")
