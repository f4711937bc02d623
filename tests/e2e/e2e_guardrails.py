"""Guardrails on time (issue #33).

- An empty body is a job sized for a first try (60 frames after 5 warm-up)
  with a default timeout_s of 30 minutes, not a day; /v1/info states it.
- Before any job of a technique ran, the 202 has no estimate; after, it
  states the job's projected duration and frame time, and the job's status
  says how long it has left while it runs (from the frames drawn).
- The estimate agrees with the measured time within a factor of 3 on a few
  jobs of other sizes and frame counts (a loaded machine moves both).
- A job projected far past its timeout_s, and the 8000x8000 job of 300
  frames (a frame far past the frame bound), are refused 400 with the
  figures, naming the field to change.
Counts and ratios only: no wall-clock bound."""

import calendar
import time

import testlib
from testlib import check

testlib.skip_without_egl()
S = testlib.TIME_SCALE


def parse_time(text):
    whole, _, frac = (text or "").rstrip("Z").partition(".")
    if not whole:
        return float("nan")
    return calendar.timegm(time.strptime(whole, "%Y-%m-%dT%H:%M:%S")) + float("0." + (frac or "0"))


def job(w, h, frames, lights=10):
    return {"technique": "forward", "frames": frames, "warmup_frames": 2,
            "scene": {"preset": "grid", "width": w, "height": h, "lights": lights}}


# The production frame bound: the 8000x8000 job is refused by it.
d = testlib.Daemon("--max-frame-seconds", "2")
try:
    info = d.json("GET", "/v1/info")[1]
    check(info.get("limits", {}).get("default_job_timeout_s") == 1800,
          "the default timeout_s is 30 minutes: %s" % info.get("limits", {}).get("default_job_timeout_s"))
    status, answer = d.json("POST", "/v1/jobs", {})
    check(status == 202 and answer.get("estimate") is None,
          "{} is accepted, with no estimate before a job of its technique ran: %s" % answer)
    spec = d.json("GET", "/v1/jobs/" + answer.get("id", ""))[1].get("spec", {})
    check(spec.get("frames") == 60 and spec.get("warmup_frames") == 5 and
          spec.get("timeout_s") == 1800,
          "{} is 60 frames after 5 warm-up with a timeout_s of 1800: %s"
          % {k: spec.get(k) for k in ("frames", "warmup_frames", "timeout_s")})
    d.json("DELETE", "/v1/jobs/" + answer.get("id", ""))
    d.wait(answer.get("id", ""))

    # The device's rate, from one job.
    first = d.run(job(64, 48, 30))
    check(first.get("status") == "done", "a first job runs: %s" % first.get("error"))

    # Estimates against measured times.
    ratios = []
    for w, h, frames in ((96, 64, 40), (48, 32, 80), (128, 96, 20)):
        status, answer = d.json("POST", "/v1/jobs", job(w, h, frames))
        est = answer.get("estimate") or {}
        check(status == 202 and est.get("duration_s", 0) > 0 and est.get("frame_s", 0) > 0,
              "%dx%d, %d frames: the 202 states an estimate: %s" % (w, h, frames, est))
        done = d.wait(answer.get("id"))
        took = parse_time(done.get("finished")) - parse_time(done.get("started"))
        if est.get("duration_s"):
            ratios.append(took / est["duration_s"])
        print("%dx%d, %d frames: estimated %.2f s, took %.2f s"
              % (w, h, frames, est.get("duration_s", -1), took))
    check(len(ratios) == 3 and all(1 / 3.0 <= r <= 3.0 for r in ratios),
          "the estimate is within a factor of 3 of the measured time: %s"
          % ["%.2f" % r for r in ratios])

    # The time left, while it runs: from the frames left and the rate so
    # far, so it falls as frames are drawn. 240 frames of 400 on, under
    # half the frames are left: the rate would have to slow 2.5 times
    # (a machine's load changing while it runs) for the figure not to fall.
    job_id = d.submit(job(64, 48, 400))
    lefts = []
    deadline = time.time() + 300 * S
    while time.time() < deadline:
        j = d.json("GET", "/v1/jobs/" + job_id)[1]
        if j.get("status") not in ("queued", "running"):
            break
        left = (j.get("seconds_left") or {}).get("frames")
        if j.get("status") == "running" and left is not None:
            lefts.append((j["progress"]["frames_done"], left))
            if lefts[-1][0] >= lefts[0][0] + 240:
                break
        time.sleep(0.2)
    d.json("DELETE", "/v1/jobs/" + job_id)
    check(len(lefts) >= 2 and lefts[-1][0] >= lefts[0][0] + 240 and lefts[-1][1] < lefts[0][1]
          and all(l >= 0 for _, l in lefts),
          "a running job states the seconds it has left, from its frames, fewer 240 frames on: "
          "%s .. %s" % (lefts[:1], lefts[-1:]))

    # Refused with the figures: past its timeout_s, and the 8000x8000 job.
    status, answer = d.json("POST", "/v1/jobs", dict(job(64, 48, 1000000), timeout_s=30))
    err = answer.get("error") or {}
    check(status == 400 and err.get("field") == "timeout_s" and
          "projected to take" in err.get("message", ""),
          "a job projected far past its timeout_s is refused with the figures: %s %s"
          % (status, answer))
    status, answer = d.json("POST", "/v1/jobs", {"technique": "forward", "frames": 300,
                                                 "scene": {"width": 8000, "height": 8000}})
    err = answer.get("error") or {}
    check(status == 400 and err.get("field") == "scene.width" and
          "projected to take" in err.get("message", ""),
          "8000x8000, 300 frames: refused with the figures: %s %s" % (status, answer))
    print("refused:", err.get("message"))
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_guardrails")
