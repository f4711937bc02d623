"""The client's verdicts, JUnit, log and usage errors that a CI engineer
relies on, each case made exactly against a scripted daemon
(fakedaemon.py: the job API with results the test chooses, no GL, no
timing), so that a case such as "every run confirming a regression was
noisy" is built, not hoped for from a busy machine:

- a percentage option refuses a bare number, with the form it expects;
- checks that judged nothing (no reference) are skipped, never passes, and
  a plain `submit --wait` on a noisy run does not say PASS;
- ab between unlike jobs compares each side with its own interference, its
  headline states the pairs it rests on and refuses a verdict on too few,
  and A against A works, with unique case names;
- a regression must be confirmed by fresh runs that enter its verdict;
- JUnit failure types by cause (regression, quality, job_failed,
  inconclusive); sweep cases carry their workload, so two sweeps in one
  pipeline never collide;
- usage errors before any job (--min-ssim without a reference), a filter
  value that matches no technique, stdout line-buffered into a pipe;
- on a terminal (a pty): a bar that ends cleanly, "run 2 of up to 4", the
  verdict in colour (not with NO_COLOR, not into a pipe).

Each check fails on the client before these fixes (43ae526)."""

import json
import os
import pty
import re
import select
import subprocess
import tempfile
import threading
import time
import xml.etree.ElementTree as ET

import testlib
from testlib import check
from clientlib import CLIENT, junit_cases
from fakedaemon import FakeDaemon, result

TMP = tempfile.mkdtemp(prefix="shadebench-client-verdicts-")


def write(name, obj):
    path = os.path.join(TMP, name)
    with open(path, "w") as f:
        json.dump(obj, f)
    return path


def run(d, *args, env=None, timeout=120):
    e = dict(os.environ, SHADEBENCH_SERVER=d.base)
    for k in ("SHADEBENCH_TOKEN", "SHADEBENCH_TOKEN_FILE", "SHADEBENCH_FAIL_INCONCLUSIVE", "NO_COLOR"):
        e.pop(k, None)
    e.update(env or {})
    return subprocess.run([CLIENT] + [str(a) for a in args], capture_output=True, text=True, env=e,
                          timeout=timeout)


def on_pty(d, *args, env=None, timeout=120):
    """The client with stderr (and stdout) on a pseudo-terminal: what a
    person at a terminal sees, escape sequences included."""
    e = dict(os.environ, SHADEBENCH_SERVER=d.base, TERM="xterm")
    e.pop("NO_COLOR", None)
    e.update(env or {})
    master, slave = pty.openpty()
    p = subprocess.Popen([CLIENT] + [str(a) for a in args], stdin=slave, stdout=slave, stderr=slave,
                         env=e, close_fds=True)
    os.close(slave)
    out = b""
    deadline = time.time() + timeout
    while time.time() < deadline:
        r, _, _ = select.select([master], [], [], 0.5)
        if r:
            try:
                chunk = os.read(master, 65536)
            except OSError:
                break
            if not chunk:
                break
            out += chunk
        elif p.poll() is not None:
            break
    p.wait(timeout=10)
    os.close(master)
    return p.returncode, out.decode(errors="replace")


def cases_by_suffix(path):
    root = ET.parse(path).getroot()
    return root, list(root.iter("testcase"))


JOB = {"technique": "forward", "frames": 10, "warmup_frames": 0, "scene": {"width": 64, "height": 48}}
job = write("job.json", JOB)

# ---- percentages take their sign ----
d = FakeDaemon(lambda spec, n: ("done", result(10.0)))
try:
    for flag, bare in (("--max-slowdown", "5"), ("--max-slowdown", "0.05"), ("--noise-tolerance", "10"),
                       ("--confidence", "95")):
        out = run(d, "ab", job, job, "--runs", "3", flag, bare)
        check(out.returncode == 2 and "%" in out.stderr and flag in out.stderr and "bare number" in out.stderr,
              "%s %s is refused with the form it expects: rc %d %s" % (flag, bare, out.returncode,
                                                                        out.stderr.strip()))
    check(d.submitted() == 0, "and nothing ran")
    out = run(d, "ab", job, job, "--runs", "3", "--max-reruns", "0", "--max-slowdown", "5%")
    check(out.returncode == 0, "5%% is taken: %s" % out.stderr[-300:])
finally:
    d.stop()

# ---- judged nothing: skipped, not passed ----
captures = [{"frame": 5, "file": "frame-000005.png"}, {"frame": 10, "file": "frame-000010.png"}]
d = FakeDaemon(lambda spec, n: ("done", result(10.0, 0.02, captures)))
try:
    junit = os.path.join(TMP, "nothing.xml")
    out = run(d, "submit", write("cap.json", dict(JOB, capture_interval=5)), "--wait", "--junit", junit)
    root, cases = cases_by_suffix(junit)
    quality = [c for c in cases if c.get("name").endswith("quality")]
    check(out.returncode == 0 and len(quality) == 2 and all(c.find("skipped") is not None for c in quality)
          and root.get("skipped") == "2",
          "captures without a reference are <skipped>, not passes: %s" % ET.tostring(root)[:600])
    check(re.search(r"^SKIP .*frame 5 quality", out.stderr, re.M) and
          not re.search(r"^PASS .*quality", out.stderr, re.M) and "judged nothing" in out.stderr,
          "the log says SKIP for them: %s" % out.stderr[-700:])
finally:
    d.stop()

# ---- a noisy run is not a PASS ----
d = FakeDaemon(lambda spec, n: ("done", result(10.0, 0.72)))
try:
    junit = os.path.join(TMP, "noisy.xml")
    out = run(d, "submit", job, "--wait", "--junit", junit)
    root, cases = cases_by_suffix(junit)
    jobcase = [c for c in cases if c.get("name").endswith(": job")]
    check(out.returncode == 0 and not re.search(r"^PASS ", out.stderr, re.M) and
          re.search(r"^NOISY .*: job", out.stderr, re.M) and "72%" in out.stderr,
          "a plain submit --wait on a noisy run says NOISY, not PASS: %s" % out.stderr[-600:])
    check(jobcase and jobcase[0].find("skipped") is not None and
          "72%" in jobcase[0].find("skipped").get("message", ""),
          "and its JUnit case is skipped with the reason")
finally:
    d.stop()

# ---- ab: unlike jobs, pairs stated, too few refused, A against A ----
def unlike(spec, n):
    # forward: 20 ms, its runs see 10% of the CPU taken; unlit: 10 ms, 50%.
    # A little spread so that the interval is an interval.
    wobble = 1 + 0.01 * ((n * 7) % 5 - 2) / 2
    if spec["technique"] == "forward":
        return "done", result(20.0 * wobble, 0.10)
    return "done", result(10.0 * wobble, 0.50)


unlit = write("unlit.json", dict(JOB, technique="unlit"))
d = FakeDaemon(unlike)
try:
    junit = os.path.join(TMP, "unlike.xml")
    out = run(d, "ab", job, unlit, "--runs", "5", "--max-reruns", "0", "--junit", junit)
    check(out.returncode == 0 and re.search(r"^B/A = 0\.\d+, 95% interval \[[0-9.]+, [0-9.]+\] over 5 pairs "
                                            r"\(none left out\): PASS", out.stderr, re.M),
          "unlike jobs, each side steady: a pass over all 5 pairs: %s" % out.stderr[-900:])
    ab = [c for c in junit_cases(junit)[1].items() if "B/A" in c[0]]
    check(ab and ab[0][1][2].get("pairs") == "5" and ab[0][1][2].get("noisy_pairs") == "0",
          "JUnit: 5 pairs, none noisy: %s" % (ab,))
    out = run(d, "ab", job, unlit, "--runs", "2", "--max-reruns", "0", "--junit", junit)
    root, cases = cases_by_suffix(junit)
    abcase = [c for c in cases if "B/A" in c.get("name")]
    check(out.returncode == 0 and "no verdict" in out.stderr and "at least 3" in out.stderr and
          not re.search(r"over \d pairs.*PASS", out.stderr) and abcase and
          abcase[0].find("skipped") is not None,
          "two pairs are too few for a verdict, and the headline says so: %s" % out.stderr[-600:])
    junit = os.path.join(TMP, "aa.xml")
    out = run(d, "ab", job, job, "--runs", "3", "--max-reruns", "0", "--junit", junit)
    root, cases = cases_by_suffix(junit)
    names = [c.get("name") for c in cases]
    check(out.returncode == 0 and "over 3 pairs (none left out): PASS" in out.stderr,
          "A against A: a pass over 3 pairs: %s" % out.stderr[-500:])
    check(len(names) == 3 and len(set(names)) == 3 and any(n.endswith(" as A: job") for n in names) and
          any(n.endswith(" as B: job") for n in names),
          "A against A has unique case names: %s" % names)
finally:
    d.stop()

# ---- a regression is confirmed by fresh runs, or not at all ----
baseline = write("baseline.json", {
    "frame_ms": {"median": 20.0}, "device": result(1)["device"], "spec": JOB, "job_id": "base",
    "gate_runs": [{"job": "b%d" % i, "frame_ms": 20.0 * (1 + 0.005 * (i - 1)),
                   "interference": {"other_cpu_share": 0.05}, "noisy": False} for i in range(3)]})


def slower_then_noisy(spec, n):
    # The first 3 runs 50% slower on a quiet machine; every later run
    # (those confirming it) with 70% of the CPU taken by others.
    ms = 30.0 * (1 + 0.005 * (n % 3 - 1))
    return "done", result(ms, 0.05 if n < 3 else 0.70)


d = FakeDaemon(slower_then_noisy)
try:
    junit = os.path.join(TMP, "unconfirmed.xml")
    out = run(d, "submit", job, "--wait", "--baseline", baseline, "--runs", "3", "--max-reruns", "6",
              "--junit", junit)
    root, cases = cases_by_suffix(junit)
    gate = [c for c in cases if "against the baseline" in c.get("name")]
    check(out.returncode == 0 and "could not be confirmed" in out.stderr and "REGRESSION" not in out.stderr
          and gate and gate[0].find("skipped") is not None and d.submitted() > 3,
          "a regression whose confirming runs were all noisy is not a FAIL resting on the first 3: "
          "rc %d %s" % (out.returncode, out.stderr[-900:]))
finally:
    d.stop()

d = FakeDaemon(lambda spec, n: ("done", result(30.0 * (1 + 0.005 * (n % 3 - 1)), 0.05)))
try:
    junit = os.path.join(TMP, "confirmed.xml")
    out = run(d, "submit", job, "--wait", "--baseline", baseline, "--runs", "3", "--max-reruns", "6",
              "--junit", junit)
    fails = list(ET.parse(junit).getroot().iter("failure"))
    check(out.returncode == 1 and "confirming on 3 more runs" in out.stderr and d.submitted() == 6 and
          re.search(r"gate over 3 baseline runs and 6 runs here \(none left out\): REGRESSION", out.stderr) and
          len(fails) == 1 and fails[0].get("type") == "regression",
          "a confirmed regression fails over all 6 runs, type regression: %s" % out.stderr[-700:])
finally:
    d.stop()

# ---- JUnit failure types by cause ----
bad = [{"frame": 10, "metrics": {"ssim": 0.5, "pdiff": {"pass": False, "failing_pixels": 900, "fov": 22.6},
                                 "flip": {"mean": 0.3}, "timing_ms": {"total": 5.0}}}]
d = FakeDaemon(lambda spec, n: ("done", result(10.0, 0.02, bad)) if n == 0 else ("failed", "shader did not compile"))
try:
    ref_job = write("ref.json", dict(JOB, capture_interval=10, reference="forward"))
    junit = os.path.join(TMP, "quality.xml")
    out = run(d, "submit", ref_job, "--wait", "--junit", junit)
    fails = list(ET.parse(junit).getroot().iter("failure"))
    check(out.returncode == 1 and [f.get("type") for f in fails] == ["quality"],
          "a quality failure is of type quality: %s" % [f.attrib for f in fails])
    junit = os.path.join(TMP, "failed.xml")
    out = run(d, "submit", job, "--wait", "--junit", junit)
    fails = list(ET.parse(junit).getroot().iter("failure"))
    check(out.returncode == 1 and [f.get("type") for f in fails] == ["job_failed"],
          "a failed job is of type job_failed: %s" % [f.attrib for f in fails])
finally:
    d.stop()

# ---- sweeps: cases carry their workload ----
def sweep_points(body, n):
    return [("forward", {"scene.lights": 8}, 10.0), ("forward", {"scene.lights": 16}, 12.0)]


d = FakeDaemon(sweep_points)
try:
    names = []
    for size in (64, 128):
        sw = write("sweep%d.json" % size, {"base": dict(JOB, scene={"width": size, "height": 48}),
                                           "vary": {"scene.lights": [8, 16]}})
        junit = os.path.join(TMP, "sweep%d.xml" % size)
        out = run(d, "sweep", sw, "--wait", "--junit", junit)
        check(out.returncode == 0, "sweep %d: %s" % (size, out.stderr[-300:]))
        names.append([c.get("name") for c in ET.parse(junit).getroot().iter("testcase")])
    check(len(names[0]) == 3 and not set(names[0]) & set(names[1]) and
          all(re.search(r"#[0-9a-f]{8}", n) for n in names[0]) and
          any("8 lights" in n and "[scene.lights=8]" in n for n in names[0]),
          "two sweeps of other bases share no case name, and points name their workload: %s" % names)
finally:
    d.stop()

# ---- usage errors before any job; filters; line-buffered stdout ----
d = FakeDaemon(lambda spec, n: ("done", result(10.0)))
try:
    out = run(d, "submit", job, "--wait", "--min-ssim", "0.99")
    check(out.returncode == 2 and "reference" in out.stderr and d.submitted() == 0,
          "--min-ssim without a reference: exit 2 before any job runs: rc %d %s" % (out.returncode, out.stderr))
    out = run(d, "ab", job, job, "--min-ssim", "0.99")
    check(out.returncode == 2 and d.submitted() == 0, "--min-ssim on ab is a usage error")
    for i in range(3):
        run(d, "submit", job, "--wait")
    out = run(d, "history", "--filter", "technique=fowrard")
    check(out.returncode == 2 and "did you mean forward" in out.stderr,
          "technique=fowrard is refused, with the nearest name: rc %d %s" % (out.returncode, out.stderr))
    out = run(d, "history", "--filter", "technique=deferred")
    check(out.returncode == 0, "a known technique without jobs is an empty history, not an error")
    # Line-buffered: the first row reaches the pipe while the client still
    # waits for the daemon on the second job.
    d.hold = {1}
    env = dict(os.environ, SHADEBENCH_SERVER=d.base)
    p = subprocess.Popen([CLIENT, "history"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env)
    lines = []

    def read_lines():
        for line in p.stdout:
            lines.append(line)
    reader = threading.Thread(target=read_lines, daemon=True)
    reader.start()
    deadline = time.time() + 10 * testlib.TIME_SCALE
    while len(lines) < 2 and time.time() < deadline:
        time.sleep(0.05)
    early = list(lines)
    d.release()
    p.wait(timeout=60)
    check(len(early) >= 2 and b"id" in early[0] and b"20261127-000000-0001" in early[1],
          "stdout is line-buffered into a pipe: the first row came while the second job's details "
          "were pending: %s" % early)
finally:
    d.stop()

# ---- on a terminal: the bar, the run count, colour ----
d = FakeDaemon(lambda spec, n: ("done", result(10.0)), polls=3)
try:
    rc, text = on_pty(d, "submit", job, "--wait", "--runs", "2", "--max-reruns", "2")
    check(rc == 0 and "run 2 of up to 4" in text, "the bar says run 2 of up to 4: %r" % text[-600:])
    # Every bar is cleared (return, erase line) before the run's line.
    check(re.search(r"\r\x1b\[Krun 1 of 2: job \S+, frame_ms", text) and
          not re.search(r"\] \d+/\d+ frames +\d+%[^\r]*\n", text),
          "the bar ends cleanly, no frozen bar above a run's line: %r" % text[-900:])
    rc, text = on_pty(d, "submit", job, "--wait")
    check("\x1b[1;32mPASS\x1b[0m" in text, "PASS in green on a terminal: %r" % text[-300:])
    rc, text = on_pty(d, "submit", job, "--wait", env={"NO_COLOR": "1"})
    check("\x1b[1;3" not in text and re.search(r"(^|\x1b\[K)PASS ", text, re.M),
          "no colour with NO_COLOR: %r" % text[-300:])
    out = run(d, "submit", job, "--wait")
    check("\x1b" not in out.stderr and "\r" not in out.stderr, "none into a pipe")
finally:
    d.stop()
testlib.finish("e2e_client_verdicts")
