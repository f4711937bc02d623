#!/usr/bin/env python3
"""A fleet on a real one-node Slurm cluster (slurmlib): shadebench sweep
--slurm runs a sweep's points as job arrays, one per device class (two node
features), and gathers them to the figures the same sweep gives on one
daemon; gathering is a pure function of the task folders; a task killed
mid-run is reported missing with Slurm's state and --resume completes it
without rerunning the others; a cancelled client cancels its array; the CI
runners' way (plan, shadebenchd --once, gather DIR...) gives the same table;
a bisection and bad device names are refused."""

import filecmp
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(__file__))
import slurmlib  # noqa: E402
from testlib import Daemon, check, finish, skip_without_egl, SHADEBENCHD, TIME_SCALE  # noqa: E402

CLIENT = os.environ.get("SHADEBENCH_CLIENT", "./shadebench")
# Coarse spheres (64 triangles, not 1,024): a point costs a third of what the
# grid's 265,000 triangles made it, and nothing here reads the geometry.
SMALL = {"technique": "forward", "frames": 4, "reference": "forward",
         "scene": {"width": 64, "height": 48, "lights": 4, "sphere_segments": 8}}
# A point that runs until it is cancelled: the grid's full spheres (about
# 30 ms a frame on a quiet 2-core box, 70 ms at load 8), no reference.
LONG = {"technique": "forward", "scene": {"width": 64, "height": 48, "lights": 4}}
SWEEP = {"base": SMALL,
         "vary": {"technique": ["forward", "deferred", "clustered_deferred"],
                  "scene.lights": [4, 32]}}
# Quality figures are exact (frames are deterministic), times are not.
SAME = ("status", "technique", "values", "worst_ssim", "worst_ssim_min", "worst_flip",
        "pdiff_failed_captures")


def client(cluster, *args, timeout=600):
    return subprocess.run([CLIENT] + [str(a) for a in args], env=cluster.env, capture_output=True,
                          text=True, timeout=timeout * TIME_SCALE)


def load(path):
    with open(path) as f:
        return json.load(f)


def same_tree(a, b):
    cmp = filecmp.dircmp(a, b)
    if cmp.left_only or cmp.right_only or cmp.diff_files or cmp.funny_files:
        return False
    _, mismatch, errors = filecmp.cmpfiles(a, b, cmp.common_files, shallow=False)
    return not mismatch and not errors and all(
        same_tree(os.path.join(a, d), os.path.join(b, d)) for d in cmp.common_dirs)


def row_key(row):
    return row["technique"] + json.dumps(row["values"], sort_keys=True)


def wait_running(cluster, array, task, timeout=120):
    deadline = time.time() + timeout * TIME_SCALE
    while time.time() < deadline:
        if (str(task), "RUNNING") in cluster.squeue(array):
            return True
        time.sleep(0.1)
    return False


def array_of(fleet, cls):
    for s in load(os.path.join(fleet, "slurm", "submissions.json"))[::-1]:
        if s["class"] == cls:
            return s["array_job_id"]
    return None


def wait_submitted(fleet, timeout=60):
    path = os.path.join(fleet, "slurm", "submissions.json")
    deadline = time.time() + timeout * TIME_SCALE
    while time.time() < deadline:
        if os.path.exists(path):
            return True
        time.sleep(0.1)
    return False


def test_two_devices_against_daemon(cluster, tmp):
    sweep_file = os.path.join(tmp, "sweep.json")
    with open(sweep_file, "w") as f:
        json.dump(SWEEP, f)
    fleet = os.path.join(tmp, "fleet")
    t0 = time.time()
    r = client(cluster, "sweep", sweep_file, "--slurm", "--partition", slurmlib.PARTITION,
               "--gres", "gpu:1", "--devices", ",".join(slurmlib.FEATURES), "--max-parallel", 2,
               "--out", fleet)
    print("sweep --slurm, 2 x 6 points: %.1f s" % (time.time() - t0))
    if not check(r.returncode == 0, "sweep --slurm exits 0: %s %s" % (r.returncode, r.stderr)):
        cluster.dump_logs()
        return
    gathered = load(os.path.join(fleet, "sweep.json"))
    check(gathered["kind"] == "fleet" and gathered["status"] == "done",
          "the gathered sweep is done: %s" % gathered["status"])
    check(gathered["progress"] == {"points_done": 12, "points_total": 12},
          "12 points gathered: %s" % gathered["progress"])
    check([d["class"] for d in gathered["devices"]] == list(slurmlib.FEATURES),
          "two device groups, in --devices order: %s" % [d["class"] for d in gathered["devices"]])
    subs = load(os.path.join(fleet, "slurm", "submissions.json"))
    check(len(subs) == 2 and len({s["array_job_id"] for s in subs}) == 2,
          "one array per device class: %s" % subs)
    for row in gathered["points"]:
        dev = row.get("device", {})
        slurm = dev.get("slurm", {})
        ok = (dev.get("node") == cluster.host and "llvmpipe" in dev.get("gl_renderer", "") and
              slurm.get("array_job_id") == array_of(fleet, dev.get("class")) and
              "array_task_id" in slurm and "job_id" in slurm)
        if not check(ok, "each row names its device, node and Slurm ids: %s" % dev):
            break
        # --device allocated: the row says which device the task opened and
        # why (the test cluster's gres, File=/dev/null, is no GPU device).
        sel = dev.get("selection", {})
        if not check(sel.get("asked") == "allocated" and "SLURM_" in sel.get("why", "") and
                     "the default choice" in sel.get("why", "") and "bus_id" in dev,
                     "each row records the device it opened and why: %s" % sel):
            break
    with open(os.path.join(fleet, "table.csv")) as f:
        head = f.readline()
    check(head.startswith("device,node,gl_renderer,"), "the CSV has a device column: %s" % head)
    for cls in slurmlib.FEATURES:
        for name in ("sweep.json", "table.csv", "report.html", "charts/speed_accuracy.svg",
                     "charts/time_vs_param.png", "charts/distribution.svg"):
            check(os.path.getsize(os.path.join(fleet, "devices", cls, name)) > 0,
                  "devices/%s/%s is written" % (cls, name))
    with open(os.path.join(fleet, "report.html")) as f:
        html = f.read()
    check(all("devices/%s/report.html" % c in html for c in slurmlib.FEATURES) and
          "Fastest technique" in html, "the fleet report links each device's and compares them")

    # The same sweep on one daemon: the same points, spec and verdict.
    d = Daemon()
    try:
        status, body = d.json("POST", "/v1/sweeps", SWEEP)
        daemon_sweep = d.wait_sweep(body["id"]) if status == 202 else {}
    finally:
        d.stop()
        d.cleanup()
    check(daemon_sweep.get("status") == "done", "the daemon's sweep is done")
    by_key = {row_key(r): r for r in daemon_sweep.get("points", [])}
    for cls in slurmlib.FEATURES:
        per = load(os.path.join(fleet, "devices", cls, "sweep.json"))
        check(per["spec"] == daemon_sweep.get("spec"), "%s: the same spec as the daemon's" % cls)
        check([row_key(r) for r in per["points"]] == [row_key(r) for r in daemon_sweep["points"]],
              "%s: the same points in the same order" % cls)
        for row in per["points"]:
            theirs = by_key.get(row_key(row), {})
            diff = {k: (row.get(k), theirs.get(k)) for k in SAME if row.get(k) != theirs.get(k)}
            check(not diff, "%s %s: the daemon's figures, %s" % (cls, row_key(row), diff))
        check(per["result"] == daemon_sweep.get("result"),
              "%s: the same verdict (pdiff_passing, largest pass) as the daemon's: %s / %s"
              % (cls, per["result"], daemon_sweep.get("result")))

    # A pure function of the task folders: twice, byte for byte, and the same
    # as what sweep --slurm gathered.
    g1, g2 = os.path.join(tmp, "g1"), os.path.join(tmp, "g2")
    for g in (g1, g2):
        r = client(cluster, "gather", fleet, "--out", g)
        check(r.returncode == 0, "gather exits 0: %s" % r.stderr)
    check(same_tree(g1, g2), "gathering twice writes the same bytes")
    check(filecmp.cmp(os.path.join(g1, "sweep.json"), os.path.join(fleet, "sweep.json"),
                      shallow=False), "gather gives what sweep --slurm gathered")
    r = client(cluster, "compare-devices", fleet)
    check(r.returncode == 0 and "dev_a frame_ms" in r.stdout and "dev_b frame_ms" in r.stdout
          and "Fastest technique" in r.stdout and "clustered_deferred lights=32" in r.stdout,
          "compare-devices prints the device table:\n%s%s" % (r.stdout, r.stderr))


def test_killed_task_and_resume(cluster, tmp):
    # Point 1 runs long enough to be cancelled while it runs (scancel comes
    # a few tenths of a second after squeue says RUNNING; 100 frames take 3
    # s or more, 8 s at load 8) and --resume runs it again whole, so no
    # longer than that (400 frames made the resume 30 s).
    long_point = dict(LONG, frames=100)
    sweep_file = os.path.join(tmp, "kill.json")
    with open(sweep_file, "w") as f:
        json.dump({"base": long_point, "vary": {"frames": [3, 100, 4]}}, f)
    fleet = os.path.join(tmp, "kill")
    proc = subprocess.Popen([CLIENT, "sweep", sweep_file, "--slurm", "--constraint", "dev_a",
                             "--gres", "gpu:1", "--max-parallel", "1", "--out", fleet],
                            env=cluster.env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    check(wait_submitted(fleet), "the array is submitted")
    array = array_of(fleet, "dev_a")
    running = wait_running(cluster, array, 1)
    check(running, "task 1 runs")
    r = cluster.run("scancel", "%s_1" % array)
    check(r.returncode == 0, "scancel of task 1: %s" % r.stderr)
    out, err = proc.communicate(timeout=300 * TIME_SCALE)
    check(proc.returncode == 1, "a partial sweep exits 1: %s %s" % (proc.returncode, err))
    gathered = load(os.path.join(fleet, "sweep.json"))
    check(gathered["status"] == "partial" and gathered["progress"]["points_done"] == 2,
          "the sweep is partial, 2 of 3: %s %s" % (gathered["status"], gathered["progress"]))
    missing = gathered["missing"]
    check(len(missing) == 1 and missing[0]["job"] == "dev_a/1" and
          missing[0].get("slurm", {}).get("state", "").startswith("CANCELLED") and
          "CANCELLED" in missing[0]["error"],
          "task 1 is missing with Slurm's state: %s" % missing)
    check(not os.path.exists(os.path.join(fleet, "tasks", "dev_a", "1")),
          "the killed task left no result folder (only its partial sibling)")
    check("missing dev_a/1" in out, "the client says what is missing: %s" % out)
    before = {i: load(os.path.join(fleet, "tasks", "dev_a", str(i), "task.json"))
              for i in (0, 2)}
    r = client(cluster, "sweep", "--slurm", "--resume", fleet)
    check(r.returncode == 0, "--resume completes the sweep: %s %s" % (r.returncode, r.stderr))
    gathered = load(os.path.join(fleet, "sweep.json"))
    check(gathered["status"] == "done" and not gathered["missing"],
          "after --resume the sweep is done: %s" % gathered["status"])
    subs = load(os.path.join(fleet, "slurm", "submissions.json"))
    check(len(subs) == 2 and subs[1]["indices"] == "1",
          "--resume submitted only the missing point: %s" % subs)
    check(all(load(os.path.join(fleet, "tasks", "dev_a", str(i), "task.json")) == before[i]
              for i in (0, 2)), "the finished points were not run again")


def test_cancelled_client_cancels_array(cluster, tmp):
    long_point = dict(LONG, frames=2000)
    sweep_file = os.path.join(tmp, "cancel.json")
    with open(sweep_file, "w") as f:
        json.dump({"base": long_point, "vary": {"scene.lights": [1, 2, 3]}}, f)
    fleet = os.path.join(tmp, "cancel")
    proc = subprocess.Popen([CLIENT, "sweep", sweep_file, "--slurm", "--gres", "gpu:1",
                             "--out", fleet], env=cluster.env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    check(wait_submitted(fleet), "the array is submitted")
    array = array_of(fleet, "default")
    check(wait_running(cluster, array, 0), "task 0 runs")
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120 * TIME_SCALE)
    check(proc.returncode == 128 + signal.SIGINT,
          "the interrupted client exits 130: %s %s" % (proc.returncode, err))
    check("cancelled Slurm array %s" % array in err, "it says it cancelled the array: %s" % err)
    deadline = time.time() + 30 * TIME_SCALE
    while cluster.squeue(array) and time.time() < deadline:
        time.sleep(0.2)
    check(not cluster.squeue(array), "no task of the array is left in Slurm: %s"
          % cluster.squeue(array))


def test_ci_runners(cluster, tmp, reference_fleet):
    """plan, shadebenchd --once on two "runners", gather of both folders."""
    sweep_file = os.path.join(tmp, "sweep.json")
    plan_dir = os.path.join(tmp, "plan-only")
    r = client(cluster, "plan", sweep_file, "--out", plan_dir)
    check(r.returncode == 0 and "6 points" in r.stdout, "plan writes 6 points: %s%s"
          % (r.stdout, r.stderr))
    runners = [os.path.join(tmp, "runner-a"), os.path.join(tmp, "runner-b")]
    for runner in runners:
        shutil.copytree(os.path.join(plan_dir, "plan"), os.path.join(runner, "plan"))
    # The two runners side by side, as CI's would be, each its points in turn.
    for n in range(3):
        procs = [(k * 3 + n, subprocess.Popen(
            [SHADEBENCHD, "--once", os.path.join(runner, "plan", "%d.json" % (k * 3 + n)),
             "--out", os.path.join(runner, "tasks", "ci_x", str(k * 3 + n))],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True))
            for k, runner in enumerate(runners)]
        for i, p in procs:
            _, err = p.communicate(timeout=300 * TIME_SCALE)
            check(p.returncode == 0, "shadebenchd --once point %d: %s" % (i, err[-500:]))
    # What a killed task leaves is never gathered.
    os.makedirs(os.path.join(runners[1], "tasks", "ci_x", "5.partial-node-1"))
    out = os.path.join(tmp, "ci-gathered")
    r = client(cluster, "gather", runners[0], runners[1], "--out", out)
    check(r.returncode == 0, "gather of two runners' folders exits 0: %s" % r.stderr)
    got = load(os.path.join(out, "sweep.json"))
    ref = load(os.path.join(reference_fleet, "devices", "dev_a", "sweep.json"))
    check(got["status"] == "done" and [d["class"] for d in got["devices"]] == ["ci_x"],
          "one device group, ci_x, complete: %s" % got["devices"])
    check([{k: p.get(k) for k in SAME} for p in got["points"]] ==
          [{k: p.get(k) for k in SAME} for p in ref["points"]],
          "the runners' table has the Slurm fleet's figures")
    r = client(cluster, "plan", sweep_file, "--out", plan_dir)
    check(r.returncode == 2 and "holds a plan already" in r.stderr, "a plan is not overwritten")


def test_refusals(cluster, tmp):
    find = os.path.join(tmp, "find.json")
    with open(find, "w") as f:
        json.dump({"base": SMALL, "find": {"param": "scene.lights", "from": 1, "to": 8,
                                           "while": "pdiff_pass"}}, f)
    r = client(cluster, "sweep", find, "--slurm", "--out", os.path.join(tmp, "find"))
    check(r.returncode == 2 and "find:" in r.stderr, "a bisection is refused: %s" % r.stderr)
    bad = os.path.join(tmp, "bad.json")
    with open(bad, "w") as f:
        json.dump({"base": SMALL, "vary": {"scene.lightz": [1]}}, f)
    r = client(cluster, "sweep", bad, "--slurm", "--out", os.path.join(tmp, "bad"))
    check(r.returncode == 2 and "vary.scene.lightz" in r.stderr,
          "a bad sweep is refused naming the field, as the daemon does: %s" % r.stderr)
    r = client(cluster, "sweep", os.path.join(tmp, "sweep.json"), "--slurm", "--devices",
               "a/b", "--out", os.path.join(tmp, "baddev"))
    check(r.returncode == 2 and "--devices" in r.stderr, "a bad class name is refused: %s"
          % r.stderr)
    r = client(cluster, "sweep", os.path.join(tmp, "sweep.json"), "--slurm", "--out",
               os.path.join(tmp, "fleet"))
    check(r.returncode == 2 and "--resume" in r.stderr,
          "a fleet folder is not reused: %s" % r.stderr)


def main():
    skip_without_egl()
    why = slurmlib.missing_requirements()
    if why:
        check(False, "a Slurm cluster cannot start here: " + why)
        finish("e2e_fleet")
    tmp = tempfile.mkdtemp(prefix="shadebench-fleet-")
    cluster = slurmlib.Cluster()
    try:
        test_two_devices_against_daemon(cluster, tmp)
        test_ci_runners(cluster, tmp, os.path.join(tmp, "fleet"))
        test_refusals(cluster, tmp)
        test_killed_task_and_resume(cluster, tmp)
        test_cancelled_client_cancels_array(cluster, tmp)
    finally:
        cluster.stop()
        shutil.rmtree(tmp, ignore_errors=True)
    finish("e2e_fleet")


if __name__ == "__main__":
    main()
