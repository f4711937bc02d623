"""The timing gate end to end: runs for a baseline (each a job of its own,
recorded in result.json), the same job against it passes, a job with many
more lights fails (compared with --allow-mismatch), a mismatched job or
device exits 2 before measuring, and a verdict that cannot be reached is
a warning or, with --fail-inconclusive, a failure. Jobs stay tiny (96x72,
spheres of 8 segments, 30 frames: a few milliseconds a frame): the gate's
statistics are under test, not the renderer. CI has two cores and runs
other tests beside this one, which is also why the "same job" check allows
60%: it must pass whatever the neighbours do, while 250 lights (7 times
slower on llvmpipe here, and still several times slower when the
neighbours take most of the CPU) must still fail."""

import json
import os
import re

import testlib
from testlib import check
from clientlib import Client, junit_cases

testlib.skip_without_egl()
JOB = {"technique": "forward", "frames": 30, "warmup_frames": 3,
       "scene": {"width": 96, "height": 72, "dynamic": True, "sphere_segments": 8}}

d = testlib.Daemon()
cl = Client(d)
try:
    job = cl.write("job", JOB)
    base_dir = cl.path("base")
    out = cl.run("submit", job, "--wait", "--runs", "3", "--out", base_dir, "--label", "commit=base")
    ids = out.stdout.split()
    check(out.returncode == 0 and len(ids) >= 3, "3 runs for a baseline, each a job: %s" % out.stderr[-300:])
    baseline = os.path.join(base_dir, "result.json")
    with open(baseline) as f:
        base = json.load(f)
    runs = base.get("gate_runs", [])
    check(len(runs) == len(ids) and all(r["frame_ms"] > 0 for r in runs) and
          [r["job"] for r in runs] == ids, "result.json records every run: %s" % runs)
    check(base.get("spec", {}).get("scene", {}).get("lights") == 10 and base.get("device", {}).get("gl_renderer"),
          "result.json has the spec and the device")
    check(all(os.path.exists(os.path.join(base_dir, "runs", i, "result.json")) for i in ids),
          "each run's files are in runs/ID/")

    # The same job passes (or cannot tell, which passes with a warning).
    junit = cl.path("same.xml")
    out = cl.run("submit", job, "--wait", "--baseline", baseline, "--runs", "3", "--max-reruns", "3",
                 "--max-slowdown", "60%", "--junit", junit)
    check(out.returncode == 0, "the same job against its baseline passes: %s" % out.stderr[-600:])
    root, cases = junit_cases(junit)
    gate = [c for n, c in cases.items() if n.endswith("median frame_ms against the baseline")]
    check(len(gate) == 1 and gate[0][2].get("outcome") in ("pass", "inconclusive") and
          float(gate[0][2]["ci_low"]) < float(gate[0][2]["ratio"]) < float(gate[0][2]["ci_high"]) and
          gate[0][1] > 0, "the gate case: outcome, ratio inside its interval, a real time: %s" % (gate,))
    check(gate and int(gate[0][2]["runs"]) + int(gate[0][2]["noisy_runs"]) >= 3,
          "judged on runs, not frames: %s %s" % (gate, out.stderr[-1500:]))
    check("baseline runs:" in out.stderr and re.search(r"^gate over \d+ baseline runs and \d+ runs here", out.stderr, re.M),
          "the runs and the verdict, with the runs it rests on, are in the log")

    # Many more lights: a different job, refused unless --allow-mismatch...
    slow = cl.write("slow", dict(JOB, scene=dict(JOB["scene"], lights=250)))
    n_before = len(d.json("GET", "/v1/jobs")[1]["jobs"])
    out = cl.run("submit", slow, "--wait", "--baseline", baseline)
    check(out.returncode == 2 and "scene.lights: 10 in the baseline, 250 here" in out.stderr,
          "a mismatched baseline exits 2 naming the field: %s" % out.stderr[-300:])
    listed = d.json("GET", "/v1/jobs")[1]["jobs"]
    check(len(listed) == n_before + 1 and listed[-1]["status"] == "cancelled",
          "the mismatched job was cancelled at once, not measured")
    # ...and with it, a regression.
    junit = cl.path("slow.xml")
    # (Noise marking off: this checks detection; a neighbour's burst must
    # not turn the verdict into "cannot tell".)
    out = cl.run("submit", slow, "--wait", "--baseline", baseline, "--allow-mismatch", "--runs", "3",
                 "--max-reruns", "6", "--max-slowdown", "60%", "--noise-tolerance", "off",
                 "--junit", junit)
    check(out.returncode == 1 and "REGRESSION" in out.stderr, "250 lights is a regression: %s" % out.stderr[-600:])
    fails = [c[0] for c in junit_cases(junit)[1].values() if c[0]]
    check(len(fails) == 1 and "slower by" in fails[0], "JUnit explains the regression: %s" % fails)
    check("confirming" in out.stderr, "a regression is confirmed on fresh runs before it fails")

    # Another device: refused before anything runs.
    other = dict(base, device=dict(base["device"], gl_renderer="Some GPU"))
    other_path = cl.path("other-device.json")
    with open(other_path, "w") as f:
        json.dump(other, f)
    out = cl.run("submit", job, "--wait", "--baseline", other_path)
    check(out.returncode == 2 and "gl_renderer" in out.stderr and not out.stdout,
          "another device exits 2 before submitting: %s" % out.stderr[-300:])

    # Too few runs to decide: a warning by default, a failure on request.
    one = cl.path("one")
    out = cl.run("submit", job, "--wait", "--runs", "1", "--out", one)
    check(out.returncode == 0, "a one-run baseline")
    args = ["submit", job, "--wait", "--baseline", os.path.join(one, "result.json"), "--runs", "1",
            "--max-reruns", "0"]
    out = cl.run(*args)
    check(out.returncode == 0 and "INCONCLUSIVE" in out.stderr and "warning" in out.stderr,
          "inconclusive passes with a warning: %s" % out.stderr[-400:])
    junit = cl.path("inc.xml")
    out = cl.run(*args, "--fail-inconclusive", "--junit", junit)
    fails = [c[0] for c in junit_cases(junit)[1].values() if c[0]]
    check(out.returncode == 3 and fails and "inconclusive" in fails[0], "--fail-inconclusive fails it (exit 3): %s" % fails)
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_gate")
