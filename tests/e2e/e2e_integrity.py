"""Timings nothing else disturbs: a job queued behind one whose metrics are
pending is timed only after those metrics finished (asserted on the records'
timestamps, not on timings); a job after a much larger one runs its timed
frames without page faults, as it does before it (the allocator keeps no
memory of earlier jobs: asserted on fault counts, not on timings); and every
result says what could have disturbed it (result.interference, per run for
repeated jobs)."""

import datetime

import testlib
from testlib import check

testlib.skip_without_egl()

# A: captures scored against a reference, so its metrics run after its
# frames; B: tiny, queued right behind it.
HEAVY = {"frames": 20, "warmup_frames": 2, "capture_interval": 5, "reference": "forward",
         "scene": {"width": 320, "height": 240, "dynamic": True}}
SMALL = {"frames": 20, "warmup_frames": 2, "scene": {"width": 160, "height": 120}}
LARGE = {"frames": 5, "warmup_frames": 0, "scene": {"width": 1080, "height": 720}}


def unix(iso):
    return datetime.datetime.strptime(iso, "%Y-%m-%dT%H:%M:%S.%fZ").replace(
        tzinfo=datetime.timezone.utc).timestamp()


def well_formed(interf, where):
    ok = check(isinstance(interf, dict), "%s: result.interference present" % where)
    if not ok:
        return
    for key in ("loadavg_start", "loadavg_end"):
        v = interf.get(key)
        check(isinstance(v, list) and len(v) == 3 and all(isinstance(x, (int, float)) and x >= 0 for x in v),
              "%s: %s is three load averages: %s" % (where, key, v))
    for key in ("other_cpu_share", "daemon_cpu_share"):
        v = interf.get(key)
        check(isinstance(v, (int, float)) and 0 <= v <= 1, "%s: %s is a share: %s" % (where, key, v))
    check(isinstance(interf.get("noisy"), bool), "%s: noisy is a boolean" % where)
    check(isinstance(interf.get("rule"), str) and "other_cpu_share" in interf["rule"],
          "%s: the rule is stated" % where)
    check(isinstance(interf.get("cpus"), int) and interf["cpus"] >= 1, "%s: cpus" % where)
    check(isinstance(interf.get("daemon_minor_faults"), int) and interf["daemon_minor_faults"] >= 0,
          "%s: daemon_minor_faults" % where)
    check(interf.get("timed_end_unix", 0) >= interf.get("timed_start_unix", 1),
          "%s: the timed region has a start and an end" % where)
    # The one noise rule (common/noise.h), applied to the figures given.
    expect = interf["other_cpu_share"] > 0.10
    check(interf["noisy"] == expect, "%s: noisy follows the rule: %s" % (where, interf))


d = testlib.Daemon()
try:
    for pair in range(2):
        a_id = d.submit(HEAVY)
        b_id = d.submit(SMALL)
        a, b = d.wait(a_id), d.wait(b_id)
        check(a["status"] == "done" and b["status"] == "done",
              "pair %d: both done (%s, %s)" % (pair, a.get("error"), b.get("error")))
        check(a["result"]["quality"]["captures_compared"] == 4, "pair %d: A's metrics ran" % pair)
        a_finished = unix(a["finished"])
        b_interf = b["result"].get("interference", {})
        well_formed(b_interf, "pair %d, B" % pair)
        well_formed(a["result"].get("interference"), "pair %d, A" % pair)
        # The structural guarantee: A is finished (metrics scored, result and
        # job.json written) before B starts, so B's first timed frame comes
        # after it. The timestamps share CLOCK_REALTIME; "finished" has
        # millisecond resolution.
        check(unix(b["started"]) >= a_finished,
              "pair %d: B started (%s) after A finished (%s)" % (pair, b["started"], a["finished"]))
        check(b_interf.get("timed_start_unix", 0) >= a_finished,
              "pair %d: B's first timed frame (%.3f) after A's metrics finished (%.3f)"
              % (pair, b_interf.get("timed_start_unix", 0), a_finished))
        # And A's own timed region lies inside A's run.
        a_interf = a["result"]["interference"]
        check(unix(a["started"]) - 0.001 <= a_interf["timed_start_unix"] <= a_interf["timed_end_unix"]
              <= a_finished, "pair %d: A's timed region lies within its run" % pair)

    # History: glibc's thresholds once moved after a large job, and the next
    # job's heap was trimmed and faulted back in every frame (88,000 faults
    # and 3.7 times the frame time for this pair). Now the daemon fixes them.
    before = d.run(SMALL)["result"]["interference"]["daemon_minor_faults"]
    check(d.run(LARGE)["status"] == "done", "a large job")
    after = d.run(SMALL)["result"]["interference"]["daemon_minor_faults"]
    print("page faults in a small job's timed frames: %d before a large job, %d after" % (before, after))
    # Without a large job in between the count still spreads from 0 to about
    # 6,000 (the driver's bins, the other threads): the bound sits between
    # that and the 88,000 of the bug.
    check(after <= max(20000, 10 * before),
          "a small job after a large one: %d page faults in its timed frames (%d before it)" % (after, before))

    # Repeated jobs: every run says what could have disturbed it.
    rep = d.run(dict(SMALL, repeat=3))
    check(rep["status"] == "done", "repeated job done: %s" % rep.get("error"))
    runs = rep["result"].get("runs", [])
    check(len(runs) == 3, "three runs")
    for i, r in enumerate(runs):
        well_formed(r.get("interference"), "run %d" % (i + 1))
    check(runs and runs[0].get("interference") == rep["result"].get("interference"),
          "the top-level interference is the first run's, like the other top-level figures")
    starts = [r["interference"]["timed_start_unix"] for r in runs if "interference" in r]
    check(starts == sorted(starts) and len(set(starts)) == len(starts), "runs are timed one after another")
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_integrity")
