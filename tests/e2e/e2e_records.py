"""No record is lost silently. Damaged job.json files (empty, garbage,
truncated) are quarantined with a log line and the jobs rebuilt from
spec.json and result.json; a damaged result.json is quarantined and its job
marked failed; what cannot be rebuilt is moved aside whole; leftover *.tmp
files go. Sweeps survive a restart: a finished one is served as before, one
stopped by SIGTERM resumes without running a point twice, one killed is
interrupted with its points kept. A full or read-only state directory
answers 507 naming it, and loses nothing."""

import json
import os
import signal
import subprocess
import tempfile
import time

import testlib
from testlib import check

testlib.skip_without_egl()
SMALL = {"frames": 5, "warmup_frames": 1, "scene": {"width": 64, "height": 48}}
WITH_REF = dict(SMALL, capture_interval=5, reference="forward")
SLOW_BASE = {"frames": 100, "warmup_frames": 0, "scene": {"width": 64, "height": 48}}


def read(path, mode="r"):
    with open(path, mode) as f:
        return f.read()


def write(path, data, mode="w"):
    with open(path, mode) as f:
        f.write(data)


def log_text(d):
    d.log.flush()
    return read(d.log_path)


def post_sweep(d, body):
    status, reply = d.json("POST", "/v1/sweeps", body)
    if status != 202:
        raise RuntimeError("sweep refused: %d %s" % (status, reply))
    return reply["id"]


def wait_for(pred, timeout=60):
    deadline = time.time() + timeout
    while time.time() < deadline:
        if pred():
            return True
        time.sleep(0.05)
    return False


# --- Damaged records -------------------------------------------------------
first = testlib.Daemon()
state = first.state
jobs_dir = os.path.join(state, "jobs")
names = ["empty", "garbage", "truncated", "with_ref", "bad_result", "nothing_left",
         "died_after_result", "died_before_metrics"]
ids, before = {}, {}
for name in names:
    ids[name] = first.submit(WITH_REF if name in ("with_ref", "died_before_metrics") else SMALL)
for name in names:
    before[name] = first.wait(ids[name])
    check(before[name]["status"] == "done", "%s: done first" % name)
check(first.stop() == 0, "first daemon exits 0")

jd = {n: os.path.join(jobs_dir, ids[n]) for n in names}
check(all(os.path.exists(os.path.join(jd[n], "spec.json")) for n in names), "every job has spec.json")
write(os.path.join(jd["empty"], "job.json"), "")
write(os.path.join(jd["garbage"], "job.json"), b"\x00\xff\xfe garbage \x01", "wb")
text = read(os.path.join(jd["truncated"], "job.json"))
write(os.path.join(jd["truncated"], "job.json"), text[: len(text) // 2])
text = read(os.path.join(jd["with_ref"], "job.json"))
write(os.path.join(jd["with_ref"], "job.json"), text[: len(text) // 3])
write(os.path.join(jd["bad_result"], "result.json"), "{\"frames\": ")
os.remove(os.path.join(jd["nothing_left"], "job.json"))
os.remove(os.path.join(jd["nothing_left"], "spec.json"))
# Killed between writing result.json and job.json: complete, so done; killed
# before the metrics completed it: interrupted.
for name in ("died_after_result", "died_before_metrics"):
    record = json.loads(read(os.path.join(jd[name], "job.json")))
    record["status"] = "running"
    write(os.path.join(jd[name], "job.json"), json.dumps(record))
result = json.loads(read(os.path.join(jd["died_before_metrics"], "result.json")))
del result["quality"]
write(os.path.join(jd["died_before_metrics"], "result.json"), json.dumps(result))
os.mkdir(os.path.join(jobs_dir, "not-a-job"))
os.mkdir(os.path.join(jobs_dir, "20990101-000000-0042"))  # an id, but empty
tmp_files = [os.path.join(jd["empty"], "job.json.tmp"), os.path.join(jd["garbage"], "timings.csv.tmp"),
             os.path.join(jobs_dir, "stray.tmp")]
for p in tmp_files:
    write(p, "half")
bad_sweep = os.path.join(state, "sweeps", "20261122-000000-0009")
os.makedirs(bad_sweep)
write(os.path.join(bad_sweep, "sweep.json"), "nonsense")

second = testlib.Daemon("--state-dir", state)
try:
    log = log_text(second)
    for name in ("empty", "garbage", "truncated", "with_ref"):
        status, job = second.json("GET", "/v1/jobs/" + ids[name])
        check(status == 200 and job["status"] == "done", "%s job.json: rebuilt as done (%s)" % (name, job.get("status")))
        check(job.get("result") == before[name]["result"], "%s: its result is served as before" % name)
        check(job.get("spec") == before[name]["spec"], "%s: its spec is as before" % name)
        check(("job.json" in log and ids[name] in log and "quarantined" in log), "%s: logged" % name)
        on_disk = json.loads(read(os.path.join(jd[name], "job.json")))
        check(on_disk["status"] == "done", "%s: a good job.json is written back" % name)
    check("empty file" in log and "not JSON" in log, "the log says why each record was unreadable")
    quarantine = os.path.join(state, "quarantine")
    q = sorted(os.listdir(quarantine)) if os.path.isdir(quarantine) else []
    for name in ("empty", "garbage", "truncated", "with_ref"):
        copies = [e for e in q if e.startswith("jobs-%s-job.json-" % ids[name]) and not e.endswith(".reason")]
        check(len(copies) == 1, "%s: the damaged job.json is kept in quarantine: %s" % (name, q))
        check(any(e.startswith(copies[0] if copies else "?") and e.endswith(".reason") for e in q),
              "%s: with a .reason beside it" % name)
    garbage_copy = [e for e in q if ids["garbage"] in e and not e.endswith(".reason")]
    check(garbage_copy and read(os.path.join(quarantine, garbage_copy[0]), "rb").startswith(b"\x00\xff\xfe"),
          "the quarantined copy holds the damaged bytes")

    status, job = second.json("GET", "/v1/jobs/" + ids["bad_result"])
    check(status == 200 and job["status"] == "failed" and "result.json" in job.get("error", "")
          and "quarantine" in job.get("error", ""),
          "a damaged result.json: job failed, saying where the file went: %s" % job.get("error"))
    check(any(ids["bad_result"] in e and "result.json" in e for e in q), "the damaged result.json is quarantined")

    job = second.json("GET", "/v1/jobs/" + ids["died_after_result"])[1]
    check(job.get("status") == "done" and job.get("result") == before["died_after_result"]["result"],
          "running on disk with a complete result.json: done (%s)" % job.get("status"))
    job = second.json("GET", "/v1/jobs/" + ids["died_before_metrics"])[1]
    check(job.get("status") == "interrupted", "running on disk, metrics missing: interrupted (%s)" % job.get("status"))
    check(second.json("GET", "/v1/jobs/" + ids["nothing_left"])[0] == 404, "a job that cannot be rebuilt is not served")
    moved = [e for e in q if e.startswith("jobs-" + ids["nothing_left"]) and not e.endswith(".reason")]
    check(len(moved) == 1 and os.path.exists(os.path.join(quarantine, moved[0], "result.json")),
          "but its whole directory is kept in quarantine: %s" % q)
    check(not os.path.exists(jd["nothing_left"]), "and moved out of jobs/")
    check(any("not-a-job" in e for e in q) and any("20990101-000000-0042" in e for e in q),
          "odd entries in jobs/ are quarantined: %s" % q)
    check(not any(os.path.exists(p) for p in tmp_files), "leftover *.tmp files are removed at start")
    check(any(e.startswith("sweeps-20261122-000000-0009") for e in q) and "sweep.json" in log,
          "a damaged sweep.json is quarantined, with a log line")
    check(second.wait(second.submit(SMALL))["status"] == "done", "the daemon works on")

    # --- Sweeps survive a restart ----------------------------------------------
    done_sweep = second.wait_sweep(post_sweep(second, {"base": SMALL, "vary": {"scene.lights": [1, 2]}}))
    check(done_sweep["status"] == "done" and len(done_sweep["points"]) == 2, "a small sweep done")
    check(os.path.exists(os.path.join(state, "sweeps", done_sweep["id"], "sweep.json")), "it is on disk")
    jobs_before = len(second.json("GET", "/v1/jobs")[1]["jobs"])
    resumed_id = post_sweep(second, {"base": SLOW_BASE, "vary": {"scene.lights": [1, 2, 3]}})
    check(wait_for(lambda: second.json("GET", "/v1/sweeps/" + resumed_id)[1].get("current_job")
                   and second.json("GET", "/v1/jobs/" + second.json("GET", "/v1/sweeps/" + resumed_id)[1]
                                   .get("current_job", "x"))[1].get("status") == "running"),
          "the long sweep is running a point")
finally:
    code = second.stop()
check(code == 0, "SIGTERM mid-sweep exits 0")
on_disk = json.loads(read(os.path.join(state, "sweeps", resumed_id, "sweep.json")))
# Stopped mid-point (the usual case), it names the point job to adopt; stopped
# between points, it has none and resumes with the next point.
check(on_disk["status"] == "queued",
      "the sweep stopped by SIGTERM is persisted as queued: %s" % on_disk.get("status"))

third = testlib.Daemon("--state-dir", state)
try:
    status, again = third.json("GET", "/v1/sweeps/" + done_sweep["id"])
    check(status == 200 and again == done_sweep, "a finished sweep is served as before after a restart")
    check(third.json("GET", "/v1/sweeps")[1]["sweeps"][0]["id"] == done_sweep["id"], "and listed")
    resumed = third.wait_sweep(resumed_id)
    check(resumed["status"] == "done", "the SIGTERMed sweep resumes and finishes: %s" % resumed.get("error"))
    rows = resumed.get("points", [])
    check([r["values"]["scene.lights"] for r in rows] == [1, 2, 3] and all(r["status"] == "done" for r in rows),
          "every point once, in order: %s" % [(r["values"], r["status"]) for r in rows])
    jobs_after = third.json("GET", "/v1/jobs")[1]["jobs"]
    check(len(jobs_after) == jobs_before + 3 and len({r["job"] for r in rows}) == 3,
          "no point ran twice: %d jobs for 3 points" % (len(jobs_after) - jobs_before))
    if on_disk.get("current_job"):
        check(on_disk["current_job"] in {r["job"] for r in rows}, "the requeued point job was adopted")

    killed_id = post_sweep(third, {"base": SLOW_BASE, "vary": {"scene.lights": [4, 5]}})
    killed_file = os.path.join(state, "sweeps", killed_id, "sweep.json")
    check(wait_for(lambda: third.json("GET", "/v1/sweeps/" + killed_id)[1].get("current_job")
                   and json.loads(read(killed_file)).get("current_job")),
          "another sweep running, and on disk as running")
    third.proc.send_signal(signal.SIGKILL)
    third.proc.wait()
    third.log.close()
finally:
    if third.alive():
        third.stop()

fourth = testlib.Daemon("--state-dir", state)
try:
    killed = fourth.json("GET", "/v1/sweeps/" + killed_id)[1]
    check(killed.get("status") == "interrupted" and "interrupted" in killed.get("error", ""),
          "a sweep killed with the daemon is interrupted, with a message: %s" % killed.get("error"))
    check(fourth.json("GET", "/v1/sweeps/" + resumed_id)[1].get("status") == "done", "the others stay done")
finally:
    testlib.stop_and_check(fourth)
for dd in (first, second, third):
    dd.cleanup(keep=testlib.failures > 0)


# --- A full disk and a read-only state directory: 507, nothing lost ----------
def try_mount_tmpfs(path):
    if os.geteuid() != 0:
        return False
    return subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", path],
                          capture_output=True).returncode == 0


base = tempfile.mkdtemp(prefix="shadebench-fs-")
mnt = os.path.join(base, "state")
os.mkdir(mnt)
mounted = try_mount_tmpfs(mnt)
try:
    if not mounted and os.geteuid() == 0:
        check(False, "the full-disk test needs a tmpfs mount (root with CAP_SYS_ADMIN)")
    else:
        full = testlib.Daemon("--state-dir", mnt)
        try:
            kept = full.run(SMALL)
            check(kept["status"] == "done", "a job on the small state directory")
            listed = full.json("GET", "/v1/jobs")[1]["jobs"]
            if mounted:
                # Fill it up.
                filler = os.path.join(mnt, "filler")
                try:
                    with open(filler, "wb") as f:
                        while True:
                            f.write(b"\0" * 65536)
                            f.flush()
                except OSError:
                    pass
                reason = "No space left on device"
            else:
                os.chmod(os.path.join(mnt, "jobs"), 0o555)
                os.makedirs(os.path.join(mnt, "sweeps"), exist_ok=True)
                os.chmod(os.path.join(mnt, "sweeps"), 0o555)
                reason = "Permission denied"
            entries = sorted(os.listdir(os.path.join(mnt, "jobs")))
            status, reply = full.json("POST", "/v1/jobs", SMALL)
            err = reply.get("error", {})
            check(status == 507 and err.get("field") == "state_dir" and mnt in err.get("message", "")
                  and reason in err.get("message", ""),
                  "a job that cannot be persisted gets 507 naming the state directory and why: %d %s" % (status, reply))
            status, reply = full.json("POST", "/v1/sweeps", {"base": SMALL, "vary": {"scene.lights": [1, 2]}})
            check(status == 507 and mnt in reply.get("error", {}).get("message", ""),
                  "so does a sweep: %d %s" % (status, reply))
            check(sorted(os.listdir(os.path.join(mnt, "jobs"))) == entries, "nothing of the refused job is left behind")
            check(full.json("GET", "/v1/jobs")[1]["jobs"] == listed, "the job list is unchanged")
            check(full.json("GET", "/v1/jobs/" + kept["id"])[1].get("result") == kept["result"],
                  "the earlier job is still served")
            check("cannot be persisted" in log_text(full), "the refusal is logged")
            if mounted:
                os.remove(filler)
                # Read-only: the same answer, with the errno saying so.
                ro = subprocess.run(["mount", "-o", "remount,ro", mnt], capture_output=True).returncode == 0
                if check(ro, "remount read-only"):
                    status, reply = full.json("POST", "/v1/jobs", SMALL)
                    check(status == 507 and "Read-only file system" in reply.get("error", {}).get("message", ""),
                          "a read-only state directory gets 507 too: %d %s" % (status, reply))
                    subprocess.run(["mount", "-o", "remount,rw", mnt], capture_output=True)
            else:
                os.chmod(os.path.join(mnt, "jobs"), 0o755)
                os.chmod(os.path.join(mnt, "sweeps"), 0o755)
            later = full.run(SMALL)
            check(later["status"] == "done", "with room again, jobs are accepted and run")
        finally:
            code = full.stop()
        check(code == 0, "daemon exits 0")
        again = testlib.Daemon("--state-dir", mnt)
        try:
            ids_now = [j["id"] for j in again.json("GET", "/v1/jobs")[1]["jobs"]]
            check(ids_now == [kept["id"], later["id"]], "after a restart every accepted job is there: %s" % ids_now)
            check(not os.path.exists(os.path.join(mnt, "quarantine")), "and nothing needed quarantine")
        finally:
            testlib.stop_and_check(again)
        full.cleanup()
finally:
    if mounted:  # never leave a mount behind, whatever failed
        subprocess.run(["umount", mnt], capture_output=True)
for leftover in (mnt, base):
    if os.path.isdir(leftover) and not os.listdir(leftover):
        os.rmdir(leftover)
testlib.finish("e2e_records")
