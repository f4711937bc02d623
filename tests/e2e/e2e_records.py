"""No record is lost silently. A damaged result.json is quarantined and its
job marked failed, naming where the file went; a job the store had as
running is done when its result.json is complete, interrupted otherwise; odd
entries in jobs/ and sweeps/ are quarantined; leftover *.tmp files go. A
damaged store (store.db) is quarantined with its reason and every job
rebuilt from its directory (spec.json and result.json), results and specs
as before; what cannot be rebuilt is moved aside whole. Sweeps survive a
restart: a finished one is served as before, one stopped by SIGTERM resumes
without running a point twice, one killed is interrupted with its points
kept. A full or read-only state directory answers 507 naming it, and loses
nothing."""

import json
import os
import signal
import subprocess
import tempfile
import time

import storelib
import testlib
from testlib import check

testlib.skip_without_egl()
SMALL = {"frames": 2, "warmup_frames": 0, "scene": {"width": 32, "height": 32}}
WITH_REF = dict(SMALL, capture_interval=2, reference="forward")
# A first point long enough for a stop to land inside it: the stop takes
# effect about half a second after the test sees the point run (70 to 135
# frames of these at load 6), and 800 frames of coarse spheres (64
# triangles, not the grid's 1,024) take 2 s or more (2.5 to 6 ms a frame).
# The resumed sweep's other points are short: before, three points of 100
# frames of the full grid took 7 s each. Under the sanitizers a frame takes
# 9 ms or more, so 400 frames last as long (3.5 s and more) and the point,
# run again whole after the restart, costs half the wait it did at 800.
SLOW_FRAMES = 400 if os.environ.get("SHADEBENCH_SANITIZERS") else 800
SLOW_BASE = {"frames": SLOW_FRAMES, "warmup_frames": 0,
             "scene": {"width": 64, "height": 48, "sphere_segments": 8}}
RESUMED_FRAMES = [SLOW_FRAMES, 2, 3]


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


def quarantined(state):
    qdir = os.path.join(state, "quarantine")
    return sorted(os.listdir(qdir)) if os.path.isdir(qdir) else []


# --- Damaged records -------------------------------------------------------
first = testlib.Daemon()
state = first.state
jobs_dir = os.path.join(state, "jobs")
names = ["plain", "with_ref", "bad_result", "nothing_left", "died_after_result", "died_before_metrics"]
ids, before = {}, {}
for name in names:
    ids[name] = first.submit(WITH_REF if name in ("with_ref", "died_before_metrics") else SMALL)
for name in names:
    before[name] = first.wait(ids[name])
    check(before[name]["status"] == "done", "%s: done first" % name)
check(first.stop() == 0, "first daemon exits 0")

jd = {n: os.path.join(jobs_dir, ids[n]) for n in names}
check(all(os.path.exists(os.path.join(jd[n], "spec.json")) for n in names), "every job has spec.json")
check(not any(os.path.exists(os.path.join(jd[n], "job.json")) for n in names),
      "and no job.json: its state is in the store")
write(os.path.join(jd["bad_result"], "result.json"), "{\"frames\": ")
# Killed between writing result.json and storing the job done: complete, so
# done; killed before the metrics completed it: interrupted.
for name in ("died_after_result", "died_before_metrics"):
    spec = json.loads(read(os.path.join(jd[name], "spec.json")))["spec"]
    storelib.set_status(state, storelib.JOBS, ids[name], "running", finished=0, spec=json.dumps(spec))
result = json.loads(read(os.path.join(jd["died_before_metrics"], "result.json")))
del result["quality"]
write(os.path.join(jd["died_before_metrics"], "result.json"), json.dumps(result))
os.mkdir(os.path.join(jobs_dir, "not-a-job"))
os.mkdir(os.path.join(jobs_dir, "20990101-000000-0042"))  # an id, but empty and unknown
# What an interrupted atomic write leaves: in a job that was running, and
# beside the records.
tmp_files = [os.path.join(jd["died_after_result"], "timings.csv.tmp"),
             os.path.join(jd["died_before_metrics"], "result.json.tmp"),
             os.path.join(jobs_dir, "stray.tmp")]
for p in tmp_files:
    write(p, "half")
bad_sweep = os.path.join(state, "sweeps", "20261122-000000-0009")
os.makedirs(bad_sweep)
write(os.path.join(bad_sweep, "sweep.json"), "nonsense")

reloaded = testlib.Daemon("--state-dir", state)
try:
    log = log_text(reloaded)
    status, job = reloaded.json("GET", "/v1/jobs/" + ids["bad_result"])
    check(status == 200 and job["status"] == "failed" and "result.json" in job.get("error", "")
          and "quarantine" in job.get("error", ""),
          "a damaged result.json: job failed, saying where the file went: %s" % job.get("error"))
    q = quarantined(state)
    check(any(ids["bad_result"] in e and "result.json" in e and not e.endswith(".reason") for e in q)
          and any(ids["bad_result"] in e and e.endswith(".reason") for e in q),
          "the damaged result.json is quarantined, with a .reason: %s" % q)
    check((storelib.row(state, storelib.JOBS, ids["bad_result"]) or {}).get("status") == "failed",
          "and the store says failed")
    check("not JSON" in log_text(reloaded), "the log says why it was unreadable")

    job = reloaded.json("GET", "/v1/jobs/" + ids["died_after_result"])[1]
    check(job.get("status") == "done" and job.get("result") == before["died_after_result"]["result"],
          "running in the store with a complete result.json: done (%s)" % job.get("status"))
    job = reloaded.json("GET", "/v1/jobs/" + ids["died_before_metrics"])[1]
    check(job.get("status") == "interrupted" and "interrupted" in job.get("error", ""),
          "running in the store, metrics missing: interrupted (%s)" % job.get("status"))
    check(reloaded.json("GET", "/v1/jobs/" + ids["plain"])[1].get("result") == before["plain"]["result"],
          "the others are served as before")
    check(any("not-a-job" in e for e in q) and any("20990101-000000-0042" in e for e in q),
          "odd entries in jobs/ are quarantined: %s" % q)
    check(reloaded.json("GET", "/v1/jobs/20990101-000000-0042")[0] == 404, "and not served")
    check(not any(os.path.exists(p) for p in tmp_files), "leftover *.tmp files are removed at start")
    check(any(e.startswith("sweeps-20261122-000000-0009") for e in q) and "sweep.json" in log,
          "a damaged sweep.json (of an earlier version) is quarantined, with a log line")
finally:
    code = reloaded.stop()
check(code == 0, "the second daemon exits 0")

# A damaged store: quarantined, every job rebuilt from its directory.
write(os.path.join(state, "store.db"), b"\x00\xff\xfe not a database \x01" * 64, "wb")
os.remove(os.path.join(jd["nothing_left"], "spec.json"))
rebuilt = testlib.Daemon("--state-dir", state)
try:
    log = log_text(rebuilt)
    q = quarantined(state)
    copies = [e for e in q if e.startswith("store-store.db-") and not e.endswith(".reason")]
    check(len(copies) == 1 and any(e == copies[0] + ".reason" for e in q),
          "the damaged store.db is kept in quarantine with its .reason: %s" % q)
    check(copies and read(os.path.join(state, "quarantine", copies[0]), "rb").startswith(b"\x00\xff\xfe"),
          "holding the damaged bytes")
    check("store.db" in log and "rebuilt" in log, "the log says what happened")
    for name in ("plain", "with_ref", "died_after_result"):
        status, job = rebuilt.json("GET", "/v1/jobs/" + ids[name])
        check(status == 200 and job["status"] == "done", "%s: rebuilt as done (%s)" % (name, job.get("status")))
        check(job.get("result") == before[name]["result"], "%s: its result is served as before" % name)
        check(job.get("spec") == before[name]["spec"], "%s: its spec is as before" % name)
    check(rebuilt.json("GET", "/v1/jobs/" + ids["died_before_metrics"])[1].get("status") == "interrupted",
          "an incomplete result.json: interrupted")
    check(rebuilt.json("GET", "/v1/jobs/" + ids["nothing_left"])[0] == 404, "a job that cannot be rebuilt is not served")
    moved = [e for e in q if e.startswith("jobs-" + ids["nothing_left"]) and not e.endswith(".reason")]
    check(len(moved) == 1 and os.path.exists(os.path.join(state, "quarantine", moved[0], "result.json")),
          "but its whole directory is kept in quarantine: %s" % q)
    check(not os.path.exists(jd["nothing_left"]), "and moved out of jobs/")
    listed = [j["id"] for j in rebuilt.json("GET", "/v1/jobs")[1]["jobs"]]
    check(listed == sorted(ids[n] for n in names if n != "nothing_left"),
          "the list has every rebuilt job: %s" % listed)
    check(rebuilt.wait(rebuilt.submit(SMALL))["status"] == "done", "the daemon works on")
finally:
    code = rebuilt.stop()
check(code == 0, "the third daemon exits 0")

second = testlib.Daemon("--state-dir", state)
try:
    # --- Sweeps survive a restart ----------------------------------------------
    done_sweep = second.wait_sweep(post_sweep(second, {"base": SMALL, "vary": {"scene.lights": [1, 2]}}))
    check(done_sweep["status"] == "done" and len(done_sweep["points"]) == 2, "a small sweep done")
    check(os.path.exists(os.path.join(state, "sweeps", done_sweep["id"], "spec.json")) and
          (storelib.row(state, storelib.SWEEPS, done_sweep["id"]) or {}).get("status") == "done",
          "it is stored")
    jobs_before = len(second.json("GET", "/v1/jobs")[1]["jobs"])
    resumed_id = post_sweep(second, {"base": SLOW_BASE, "vary": {"frames": RESUMED_FRAMES}})
    check(wait_for(lambda: second.json("GET", "/v1/sweeps/" + resumed_id)[1].get("current_job")
                   and second.json("GET", "/v1/jobs/" + second.json("GET", "/v1/sweeps/" + resumed_id)[1]
                                   .get("current_job", "x"))[1].get("status") == "running"),
          "the long sweep is running a point")
    point = second.json("GET", "/v1/jobs/" + second.json("GET", "/v1/sweeps/" + resumed_id)[1]
                        .get("current_job", "x"))[1]
    print("SIGTERM with the point at frame %s of %d"
          % (point.get("progress", {}).get("frames_done"), SLOW_FRAMES))
finally:
    code = second.stop()
check(code == 0, "SIGTERM mid-sweep exits 0")
stored = storelib.row(state, storelib.SWEEPS, resumed_id) or {}
on_disk = dict(stored.get("extra") or {}, status=stored.get("status"))
# Stopped mid-point (the usual case), it names the point job to adopt; stopped
# between points, it has none and resumes with the next point.
print("the sweep stopped %s" % ("in point job %s" % on_disk["current_job"]
                                 if on_disk.get("current_job") else "between points"))
check(on_disk["status"] == "queued",
      "the sweep stopped by SIGTERM is stored as queued: %s" % on_disk.get("status"))

third = testlib.Daemon("--state-dir", state)
try:
    status, again = third.json("GET", "/v1/sweeps/" + done_sweep["id"])
    check(status == 200 and again == done_sweep, "a finished sweep is served as before after a restart")
    check(third.json("GET", "/v1/sweeps")[1]["sweeps"][0]["id"] == done_sweep["id"], "and listed")
    resumed = third.wait_sweep(resumed_id)
    check(resumed["status"] == "done", "the SIGTERMed sweep resumes and finishes: %s" % resumed.get("error"))
    rows = resumed.get("points", [])
    check([r["values"]["frames"] for r in rows] == RESUMED_FRAMES and all(r["status"] == "done" for r in rows),
          "every point once, in order: %s" % [(r["values"], r["status"]) for r in rows])
    jobs_after = third.json("GET", "/v1/jobs")[1]["jobs"]
    check(len(jobs_after) == jobs_before + 3 and len({r["job"] for r in rows}) == 3,
          "no point ran twice: %d jobs for 3 points" % (len(jobs_after) - jobs_before))
    if on_disk.get("current_job"):
        check(on_disk["current_job"] in {r["job"] for r in rows}, "the requeued point job was adopted")

    killed_id = post_sweep(third, {"base": SLOW_BASE, "vary": {"scene.lights": [4, 5]}})
    check(wait_for(lambda: third.json("GET", "/v1/sweeps/" + killed_id)[1].get("current_job")
                   and ((storelib.row(state, storelib.SWEEPS, killed_id) or {}).get("extra") or {})
                   .get("current_job")),
          "another sweep running, and stored as running")
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
for dd in (first, reloaded, rebuilt, second, third):
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
                testlib.fill_disk(filler)
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
                # Read-only: the same answer, with the errno saying so. The
                # store's database is open for writing, so the kernel refuses
                # to remount the whole state directory read-only under it;
                # jobs/ (a read-only bind mount over itself) is where a new
                # job would go.
                jobs_mnt = os.path.join(mnt, "jobs")
                ro = (subprocess.run(["mount", "--bind", jobs_mnt, jobs_mnt], capture_output=True).returncode == 0
                      and subprocess.run(["mount", "-o", "remount,bind,ro", jobs_mnt],
                                         capture_output=True).returncode == 0)
                if check(ro, "jobs/ mounted read-only"):
                    status, reply = full.json("POST", "/v1/jobs", SMALL)
                    check(status == 507 and "Read-only file system" in reply.get("error", {}).get("message", ""),
                          "a read-only state directory gets 507 too: %d %s" % (status, reply))
                subprocess.run(["umount", jobs_mnt], capture_output=True)
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
        subprocess.run(["umount", os.path.join(mnt, "jobs")], capture_output=True)
        subprocess.run(["umount", mnt], capture_output=True)
for leftover in (mnt, base):
    if os.path.isdir(leftover) and not os.listdir(leftover):
        os.rmdir(leftover)
testlib.finish("e2e_records")
