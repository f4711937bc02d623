"""The safety net never changes timed work (issue #33).

- A job whose first frame is slow (a loaded or throttled machine, here
  simulated: SHADEBENCH_DEBUG_STALL_FIRST_FRAME_MS makes every wait of the
  first frame a run draws sleep first) is timed exactly as one whose first
  frame is not: every timed frame drawn whole, no piece sliced, the same rule
  with 1 and with 4 warm-up frames. (Before, a piece that measured a second
  in the first warm-up frame was drawn in tiles in every timed frame, so the
  rule depended on the load during that one frame.)
- A job whose whole frame would hold the render thread past the bound
  (--max-frame-seconds) fails before timing, naming the figures that decided
  it (the frame's measured cost, the limit) and how to run it; with
  "accept_sliced_timing": true it runs in slices instead, and every figure
  says so (result.timing, timings.csv's drawn_whole column).

Counts and orders only: no wall-clock bound, so a loaded machine passes."""

import csv
import os

import testlib
from testlib import check

testlib.skip_without_egl()

JOB = {"technique": "forward", "frames": 4, "warmup_frames": 1, "capture_interval": 0,
       "scene": {"preset": "grid", "width": 64, "height": 48, "lights": 16}}


def rule_of(done):
    """What the result says of how the timed frames were drawn."""
    res = done.get("result") or {}
    timing = res.get("timing") or {}
    budget = res.get("gpu_budget") or {}
    return (timing.get("rule"), timing.get("frames_whole"), timing.get("frames_sliced"),
            budget.get("pieces_sliced"))


def drawn_column(d, done):
    """timings.csv's drawn_whole column (1 or 0), one entry per timed frame."""
    path = os.path.join(d.state, "jobs", done["id"], "timings.csv")
    try:
        with open(path) as f:
            return [row.get("drawn_whole") for row in csv.DictReader(f)]
    except OSError:
        return None


# Every daemon here mostly sleeps (the stalls) or draws small frames, so all
# four run side by side: each job is submitted first, and the results are
# read in turn (each daemon still runs its own jobs one after another).
#
# The production bound, not the tests' roomier one: the stall must not
# decide under it either.
calm = testlib.Daemon("--max-frame-seconds", "2")
stalled = testlib.Daemon("--max-frame-seconds", "2",
                         env={"SHADEBENCH_DEBUG_STALL_FIRST_FRAME_MS": "150"})
# A first frame so slow that its measure gives up (past 4 times the bound):
# a stall a wait of 4.2 times the bound gives up at the first measured tile,
# in OSL's first shading, which must then be made anew (with the
# run_recreate_technique after a give-up left out, the capture below
# differed from the calm daemon's in 975 pixels; with the former bound of
# 2 s and stall of 3 s the measure gave up later, the capture came out the
# same without it, and the stalls took 95 s; now about 17 s). The bound is 4
# times the most the second measure of this OSL frame came to at load 8-10
# (0.25 s, side by side with the other daemons here; 0.5 s passed as well);
# bound and stall scale with SHADEBENCH_TIME_SCALE.
VERY_BOUND_S = 1.0 * testlib.TIME_SCALE
very = testlib.Daemon("--max-frame-seconds", "%g" % VERY_BOUND_S,
                      env={"SHADEBENCH_DEBUG_STALL_FIRST_FRAME_MS":
                           "%d" % (4.2 * VERY_BOUND_S * 1000)})
# A frame over the bound: refused before timing with its figures, or, once
# the job accepts it, timed in slices and marked so.
# A frame of tens of milliseconds against a bound of 20 ms; with
# SHADEBENCH_SLICE_MS every piece that is cut at all is cut in at least 4
# tiles (slices of a second: few tiles, since on a loaded box every tile
# costs a round trip of tens of milliseconds whatever its size).
d = testlib.Daemon("--max-frame-seconds", "0.02", env={"SHADEBENCH_SLICE_MS": "1000"})
daemons = (calm, stalled, very, d)
OSL = {"technique": "osl", "frames": 2, "warmup_frames": 1, "capture_interval": 2,
       "scene": {"preset": "grid", "width": 64, "height": 48}}
BIG = {"technique": "forward", "frames": 3, "warmup_frames": 1,
       "scene": {"preset": "grid", "width": 96, "height": 64, "lights": 256}}
try:
    # The longest first: the stalled daemon's and the very stalled one's.
    stalled_ids = [stalled.submit(dict(JOB, warmup_frames=w)) for w in (1, 4)]
    very_id = very.submit(OSL)
    calm_ids = [calm.submit(dict(JOB, warmup_frames=w)) for w in (1, 4)]
    calm_osl_id = calm.submit(OSL)
    big_id = d.submit(BIG)
    big_sliced_id = d.submit(dict(BIG, accept_sliced_timing=True))

    for warmup, a_id, b_id in zip((1, 4), calm_ids, stalled_ids):
        a, b = calm.wait(a_id), stalled.wait(b_id)
        ra, rb = rule_of(a), rule_of(b)
        print("warmup %d: calm %s, stalled first frame %s" % (warmup, ra, rb))
        check(a.get("status") == "done" and b.get("status") == "done",
              "warmup %d: both run: %s %s" % (warmup, a.get("error"), b.get("error")))
        check(ra == ("whole", 4, 0, 0),
              "warmup %d: every timed frame drawn whole, no piece sliced: %s" % (warmup, ra))
        check(rb == ra, "warmup %d: a slow first frame changes nothing of the timed frames: "
              "%s against %s" % (warmup, rb, ra))
        check(drawn_column(calm, a) == ["1"] * 4 and drawn_column(stalled, b) == ["1"] * 4,
              "warmup %d: timings.csv says each timed frame was drawn whole: %s %s"
              % (warmup, drawn_column(calm, a), drawn_column(stalled, b)))
        timing = (b.get("result") or {}).get("timing") or {}
        check(timing.get("measuring_runs", 0) >= 1 and timing.get("whole_frame_s", -1) > 0,
              "warmup %d: the result states the measure that decided it: %s" % (warmup, timing))

    # Drawn through once, measured again, timed whole, and the same pixels,
    # OSL's first shading included (cut short, it must not pass for done).
    a, b = calm.wait(calm_osl_id), very.wait(very_id)
    timing = (b.get("result") or {}).get("timing") or {}
    print("OSL, first frame stalled %.1f s a wait against a %g s bound: %s" % (
        4.2 * VERY_BOUND_S, VERY_BOUND_S, {k: timing.get(k) for k in (
            "rule", "measuring_runs", "first_frame_estimate_s", "settling_frame_s",
            "second_estimate_s")}))
    check(b.get("status") == "done" and timing.get("rule") == "whole" and
          timing.get("measuring_runs") == 3 and (timing.get("settling_frame_s") or 0) > 0,
          "a first frame far over the bound is measured again and timed whole: %s %s"
          % (b.get("error"), timing))
    if a.get("status") == "done" and b.get("status") == "done":
        diff = testlib.png_diff(os.path.join(calm.state, "jobs", a["id"], "frame-000002.png"),
                                os.path.join(very.state, "jobs", b["id"], "frame-000002.png"))
        check(diff is not None and diff["differing_pixels"] == 0,
              "and renders the same pixels as the calm daemon: %s" % diff)

    info = d.json("GET", "/v1/info")[1]
    check((info.get("limits") or {}).get("max_frame_seconds") == 0.02,
          "/v1/info states max_frame_seconds: %s" % (info.get("limits") or {}).get("max_frame_seconds"))
    done = d.wait(big_id)
    err = done.get("error") or ""
    print("over the bound: %s: %s" % (done.get("status"), err))
    check(done.get("status") == "failed" and "before timing" in err and
          "--max-frame-seconds 0.02" in err and "accept_sliced_timing" in err and
          "scene.width" in err and " s " in err,
          "a frame over the bound fails before timing, with its figures and what to change: %s"
          % err)
    check(done.get("progress", {}).get("frames_done") == 0,
          "no frame of it was timed: %s" % done.get("progress"))
    done = d.wait(big_sliced_id)
    res = done.get("result") or {}
    timing = res.get("timing") or {}
    print("accepted in slices: %s %s" % (done.get("status"), timing))
    check(done.get("status") == "done" and timing.get("rule") == "sliced" and
          timing.get("frames_sliced") == 3 and timing.get("frames_whole") == 0 and
          res.get("gpu_budget", {}).get("pieces_sliced", 0) >= 3,
          "with accept_sliced_timing the job runs in slices, and says so: %s %s"
          % (done.get("error"), timing))
    check(drawn_column(d, done) == ["0"] * 3,
          "timings.csv marks every timed frame sliced: %s" % drawn_column(d, done))
    check((done.get("figures") or {}).get("sliced") is True or
          (res.get("frame_ms") or {}).get("sliced") is True,
          "the headline figures are marked sliced: %s %s"
          % (done.get("figures"), res.get("frame_ms")))
finally:
    for daemon in daemons:
        testlib.stop_and_check(daemon)
testlib.finish("e2e_timing_rule")
