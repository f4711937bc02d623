"""Results survive the daemon: kill -9 it mid-job, restart on the same state
directory, and every finished job is served byte for byte as before, the
killed job is "interrupted" with a message, a queued job runs; SIGTERM
puts the running job back at the head of the queue (stored as queued, run
again on the next start) and exits 0; retention removes only the oldest
finished jobs, their rows and directories."""

import hashlib
import os
import signal
import time

import storelib
import testlib
from testlib import check

testlib.skip_without_egl()
SMALL = {"frames": 6, "warmup_frames": 1, "capture_interval": 3,
         "scene": {"width": 128, "height": 96, "dynamic": True}}
LONG = {"frames": 1000000, "warmup_frames": 0, "timeout_s": 0, "scene": {"width": 32, "height": 32}}


def digest_dir(path):
    out = {}
    for name in sorted(os.listdir(path)):
        with open(os.path.join(path, name), "rb") as f:
            out[name] = hashlib.sha256(f.read()).hexdigest()
    return out


def wait_running(d, job_id):
    deadline = time.time() + 30
    while d.json("GET", "/v1/jobs/" + job_id)[1]["status"] != "running" and time.time() < deadline:
        time.sleep(0.05)


first = testlib.Daemon()
state = first.state
done_id = first.submit(dict(SMALL, reference="forward"))
done_before = first.wait(done_id)
check(done_before["status"] == "done", "first job done")
files_before = digest_dir(os.path.join(state, "jobs", done_id))
check("result.json" in files_before and "frame-000006.png" in files_before, "its files are on disk")
killed_id = first.submit(LONG)
wait_running(first, killed_id)
queued_id = first.submit(SMALL)
first.proc.send_signal(signal.SIGKILL)
first.proc.wait()
first.log.close()

# A new daemon on the same state directory.
second = testlib.Daemon("--state-dir", state)
try:
    status, again = second.json("GET", "/v1/jobs/" + done_id)
    check(status == 200 and again["status"] == "done", "the finished job is served after kill -9")
    check(again.get("result") == done_before.get("result"), "its result is unchanged")
    files_after = digest_dir(os.path.join(state, "jobs", done_id))
    check(files_after == files_before, "its files are byte-for-byte intact: %s differ"
          % sorted(k for k in set(files_before) | set(files_after)
                   if files_before.get(k) != files_after.get(k)))
    png = os.path.join(second.tmp, "f.png")
    check(second.download("/v1/jobs/%s/flip/6.png" % done_id, png) == 200, "its images are served")
    status, killed = second.json("GET", "/v1/jobs/" + killed_id)
    check(killed["status"] == "interrupted" and "interrupted" in killed.get("error", ""),
          "the killed job is interrupted, with a message: %s" % killed.get("error"))
    check(second.wait(queued_id)["status"] == "done", "the queued job ran after the restart")
    listed = [j["id"] for j in second.json("GET", "/v1/jobs")[1]["jobs"]]
    check(listed == sorted(listed) and {done_id, killed_id, queued_id} <= set(listed),
          "every job is listed, oldest first")
    new_id = second.submit(SMALL)
    check(new_id not in (done_id, killed_id, queued_id), "new ids never clash with reloaded ones")
    check(second.wait(new_id)["status"] == "done", "and new jobs run")

    # SIGTERM with a job running: it goes back to the queue, state written, exit 0.
    term_id = second.submit(LONG)
    wait_running(second, term_id)
    after_id = second.submit(SMALL)  # queued behind it: must stay behind it
    t0 = time.time()
finally:
    code = second.stop()
check(code == 0 and time.time() - t0 < 30, "SIGTERM mid-job exits 0 quickly (%s)" % code)
on_disk = storelib.row(state, storelib.JOBS, term_id) or {}
check(on_disk.get("status") == "queued" and on_disk.get("error") is None and on_disk.get("started") == 0,
      "the SIGTERMed job is stored as queued, not failed: %s" % on_disk.get("status"))
check((storelib.row(state, storelib.JOBS, after_id) or {}).get("status") == "queued",
      "the job behind it stays queued")

third = testlib.Daemon("--state-dir", state, "--keep-jobs", "2")
try:
    wait_running(third, term_id)
    status, term = third.json("GET", "/v1/jobs/" + term_id)
    check(status == 200 and term["status"] == "running",
          "the SIGTERMed job runs again first on the next start: %s" % term.get("status"))
    check(third.json("GET", "/v1/jobs/" + after_id)[1]["status"] == "queued",
          "the job queued behind it waits its turn")
    check(third.json("DELETE", "/v1/jobs/" + term_id)[0] in (200, 202), "it can be cancelled")
    check(third.wait(term_id)["status"] == "cancelled", "a DELETE cancels it for good")
    check(third.wait(after_id)["status"] == "done", "then the next job runs")
    # Retention runs right after each job finishes; give it a moment.
    deadline = time.time() + 10
    while time.time() < deadline and len(os.listdir(os.path.join(state, "jobs"))) > 2:
        time.sleep(0.1)
    remaining = sorted(os.listdir(os.path.join(state, "jobs")))
    check(remaining == sorted([term_id, after_id]),
          "--keep-jobs 2 keeps the newest two finished (%s, %s): %s; statuses %s"
          % (term_id, after_id, remaining,
             [(j["id"], j["status"]) for j in third.json("GET", "/v1/jobs")[1]["jobs"]]))
    check(storelib.ids(state) == sorted([term_id, after_id]) and
          [j["id"] for j in third.json("GET", "/v1/jobs")[1]["jobs"]] == sorted([term_id, after_id]),
          "and their rows: the store and the list hold the same two: %s" % storelib.ids(state))
    check(third.json("GET", "/v1/jobs/" + done_id)[0] == 404, "a removed job is gone from the API")
    check(os.path.isdir(state), "the state directory itself stays")
finally:
    third.stop()
check(third.proc.returncode == 0, "daemon exits 0")
second.cleanup()
first.cleanup(keep=testlib.failures > 0)
third.cleanup()
testlib.finish("e2e_persist")
