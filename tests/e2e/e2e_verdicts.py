"""Verdicts a user can defend, end to end, with tiny jobs: a gate or an A/B
comparison that cannot decide is never a plain pass (JUnit <skipped> with
its reason; exit 3 when CI asks to fail on it, by flag or environment);
ab speaks of A and B; one log line a run; JUnit names from the job file as
written; history draws one series per workload, with a workload column
and ticks on round times; a technique sweep's verdict does not contradict
itself and its accuracy axis does not zoom into noise; a cancelled sweep
says it is partial; the job report says what disturbed the run and prints
numbers for people; and the client's errors (a mistyped flag, a missing
file, a missing or wrong token) say what is wrong.

The undecided verdicts are made deterministic by giving the statistics too
few runs (one run a side, no reruns), never by hoping for noise, so that a
loaded CI box cannot flip them."""

import json
import os
import re
import time
import xml.etree.ElementTree as ET

import testlib
from testlib import check
from clientlib import Client, junit_cases

testlib.skip_without_egl()
TOKEN = "verdicts-token"
SMALL = {"technique": "forward", "frames": 4, "warmup_frames": 0,
         "scene": {"width": 64, "height": 48}}

token_file = os.path.join(os.environ.get("TMPDIR", "/tmp"), "shadebench-verdicts-%d" % os.getpid())
with open(token_file, "w") as f:
    f.write(TOKEN + "\n")
d = testlib.Daemon("--token", token_file)
cl = Client(d, TOKEN)
AUTH = {"Authorization": "Bearer " + TOKEN}


def api(method, path, body=None):
    return d.json(method, path, body, headers=AUTH)


def wait_sweep(sweep_id):
    deadline = time.time() + 300 * testlib.TIME_SCALE
    while True:
        body = api("GET", "/v1/sweeps/%s?wait=30" % sweep_id)[1]
        if body.get("status") not in ("queued", "running") or time.time() > deadline:
            return body


def svg_layout(path):
    text = open(path).read()
    m = re.search(r'<metadata id="shadebench-chart">(.*?)</metadata>', text, re.S)
    raw = m.group(1).replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&") if m else "{}"
    return json.loads(raw)


try:
    job = cl.write("small", SMALL)

    # ---- the gate, undecided: one run a side, no reruns ----
    one = cl.path("one")
    out = cl.run("submit", job, "--wait", "--runs", "1", "--out", one)
    check(out.returncode == 0, "a one-run baseline: %s" % out.stderr[-300:])
    base = os.path.join(one, "result.json")
    junit = cl.path("inc.xml")
    args = ["submit", job, "--wait", "--baseline", base, "--runs", "1", "--max-reruns", "0",
            "--junit", junit]
    out = cl.run(*args)
    root, cases = junit_cases(junit)
    gate = ET.parse(junit).getroot().find(".//testcase[skipped]")
    check(out.returncode == 0 and gate is not None and root.get("skipped") == "1" and
          root.get("failures") == "0",
          "an undecided gate exits 0 but is <skipped> in JUnit, not passed: %s" % out.stderr[-400:])
    reason = gate.find("skipped").get("message") if gate is not None else ""
    check(reason.startswith("inconclusive: ") and "too few usable runs" in reason,
          "the skipped case says why it could not decide: %s" % reason)
    check("INCONCLUSIVE" in out.stderr and "0 failed, 1 inconclusive" in out.stderr and
          "SHADEBENCH_FAIL_INCONCLUSIVE" in out.stderr,
          "the log says inconclusive, not PASS, and how to fail on it: %s" % out.stderr[-500:])
    check("at most 0 extra" in out.stderr and re.search(r"^run 1 of 1: job \S+, frame_ms [0-9.]+ ms",
                                                        out.stderr, re.M),
          "the log states the rerun budget and gives one line a run: %s" % out.stderr[:600])
    check(not re.search(r": (running|queued|[a-z_]+), \d+/\d+ frames", out.stderr),
          "no progress lines burying the run lines in a CI log")
    out = cl.run(*args, extra_env={"SHADEBENCH_FAIL_INCONCLUSIVE": "1"})
    fails = [c for c in ET.parse(junit).getroot().iter("failure")]
    check(out.returncode == 3 and len(fails) == 1 and fails[0].get("type") == "inconclusive",
          "SHADEBENCH_FAIL_INCONCLUSIVE=1: exit 3, a failure of type inconclusive: rc %d %s"
          % (out.returncode, out.stderr[-300:]))
    out = cl.run(*args, "--no-fail-inconclusive", extra_env={"SHADEBENCH_FAIL_INCONCLUSIVE": "1"})
    check(out.returncode == 0, "--no-fail-inconclusive overrides the environment")
    out = cl.run("list", extra_env={"SHADEBENCH_FAIL_INCONCLUSIVE": "perhaps"})
    check(out.returncode == 2 and "SHADEBENCH_FAIL_INCONCLUSIVE" in out.stderr,
          "a bad environment value is refused, naming the variable")

    # ---- ab, undecided: one pair ----
    junit = cl.path("ab.xml")
    out = cl.run("ab", job, job, "--runs", "1", "--max-reruns", "0", "--junit", junit)
    check(out.returncode == 0 and "INCONCLUSIVE" in out.stderr and "baseline" not in out.stderr,
          "ab's undecided verdict never speaks of a baseline: %s" % out.stderr[-600:])
    check(ET.parse(junit).getroot().find(".//testcase/skipped") is not None,
          "ab's undecided case is <skipped> too")
    lines = [l for l in out.stderr.splitlines() if re.match(r"^[AB] 1 of 1: job ", l)]
    check(len(lines) == 2, "one log line a run, A and B: %s" % out.stderr[:500])

    # ---- JUnit names from the file as written ----
    junit = cl.path("names.xml")
    out = cl.run("submit", job, "--wait", "--junit", junit)
    names = sorted(junit_cases(junit)[1])
    check(out.returncode == 0 and names and names[0].startswith("forward 64x48 #") and
          all("lights" not in n and "still" not in n for n in names),
          "names carry what the file says, not the daemon's defaults: %s" % names)

    # ---- history: one series per workload ----
    wider = cl.write("wider", dict(SMALL, scene={"width": 96, "height": 64}))
    out = cl.run("submit", wider, "--wait")
    check(out.returncode == 0, "a second workload")
    hist = cl.path("hist")
    out = cl.run("history", "--filter", "technique=forward", "--out", hist)
    check(out.returncode == 0, "history: %s" % out.stderr[-300:])
    header = out.stdout.splitlines()[0] if out.stdout else ""
    check("workload" in header and "others' CPU" in header and "96x64" in out.stdout and
          "64x48" in out.stdout, "the table has workload and noise columns: %s" % out.stdout[:400])
    # One workload hash everywhere: the JUnit name's (from the file as
    # written) is the one history prints (from the daemon's spec).
    junit_hash = re.search(r"#([0-9a-f]{8})", names[0]).group(1) if names else "?"
    rows = [l for l in out.stdout.splitlines() if "64x48" in l]
    check(rows and all("#" + junit_hash in l for l in rows),
          "history prints the JUnit name's workload hash #%s: %s" % (junit_hash, rows))
    svg = open(os.path.join(hist, "trend.svg")).read()
    series = re.findall(r'class="series" data-series="([^"]+)"', svg)
    check(len(series) == 2 and all(s.startswith("forward#") for s in series),
          "two workloads, two series: %s" % series)
    ticks = re.findall(r'class="tick" data-t="(\d+)"[^>]*>([^<]+)<', svg)
    exact = all(time.strftime("%H:%M:%S" if len(lab) == 8 else "%H:%M", time.gmtime(int(t))) == lab
                for t, lab in ticks if len(lab) in (5, 8))
    check(ticks and exact, "every tick label is its tick's exact time: %s" % ticks[:4])

    # ---- a sweep over techniques: the reproducer ----
    status, reply = api("POST", "/v1/sweeps", {
        "base": dict(SMALL, capture_interval=4, reference="forward"),
        "vary": {"technique": ["forward_plus", "clustered_forward"]}})
    check(status == 202, "a technique sweep: %s" % reply)
    sw = wait_sweep(reply.get("id"))
    check(sw.get("status") == "done", "it ends: %s" % sw.get("status"))
    html = d.request("GET", "/v1/sweeps/%s/report.html" % sw["id"], headers=AUTH)[2].decode()
    check("none passes" not in html and "none</b>" not in html and "judged" in html,
          "its verdict does not say 'none passes' when points pass")
    path = cl.path("sa.svg")
    with open(path, "wb") as f:
        f.write(d.request("GET", "/v1/sweeps/%s/charts/speed_accuracy.svg" % sw["id"],
                          headers=AUTH)[2])
    layout = svg_layout(path)
    check(layout.get("y_range", [1])[0] <= 0.99, "the SSIM axis starts at 0.99 or below: %s"
          % layout.get("y_range"))
    verdict_front = re.findall(r"Pareto front of speed against worst SSIM", html)
    drawn = [p for p in layout.get("points", []) if p.get("pareto")]
    check(verdict_front and drawn, "the verdict and the chart both have a front")

    # ---- a cancelled sweep is partial, and says so ----
    status, reply = api("POST", "/v1/sweeps", {"base": dict(SMALL, timeout_s=0), "vary": {"frames": [4, 1000000]}})
    sid = reply.get("id")
    deadline = time.time() + 120 * testlib.TIME_SCALE
    while time.time() < deadline:
        s = api("GET", "/v1/sweeps/%s" % sid)[1]
        if s.get("progress", {}).get("points_done", 0) >= 1 or s.get("status") not in ("queued", "running"):
            break
        time.sleep(0.2)
    check(api("DELETE", "/v1/sweeps/%s" % sid)[0] in (200, 202), "the sweep is cancelled")
    s = wait_sweep(sid)
    html = d.request("GET", "/v1/sweeps/%s/report.html" % sid, headers=AUTH)[2].decode()
    # The cancel lands on the sweep's last point (one of a million frames):
    # the sweep is cancelled, not done, and that point is not counted done.
    ran = [p for p in s.get("points", []) if p.get("status") != "cancelled"]
    check(s.get("status") == "cancelled" and
          s.get("progress", {}).get("points_done") == len(ran) == 1,
          "a sweep cancelled during its last point is cancelled, its cancelled point not done: "
          "%s %s" % (s.get("status"), s.get("progress")))
    check("A partial sweep" in html and
          "Not measured" in html,
          "a cancelled sweep's report says it is partial and names the point it lacks: %s %s"
          % (s.get("status"), [(p.get("values"), p.get("status")) for p in s.get("points", [])]))
    with open(path, "wb") as f:
        f.write(d.request("GET", "/v1/sweeps/%s/charts/time_vs_param.svg" % sid, headers=AUTH)[2])
    layout = svg_layout(path)
    check("partial" in layout.get("title", "") and
          any(l.startswith("Not drawn") for l in layout.get("footer", [])),
          "its chart says partial and what it could not draw: %s" % layout.get("footer"))

    # ---- the job report: noise and numbers for people ----
    jid = api("POST", "/v1/jobs", dict(SMALL, capture_interval=4, reference="forward"))[1]["id"]
    while api("GET", "/v1/jobs/%s?wait=30" % jid)[1].get("status") in ("queued", "running"):
        pass
    html = d.request("GET", "/v1/jobs/%s/report.html" % jid, headers=AUTH)[2].decode()
    check(("Quiet run:" in html or "A noisy run:" in html) and "of the machine's CPU time" in html,
          "the job report says what disturbed the run")
    check("22.600000000000001" not in html and "&quot;fov&quot;: 22.6," in html,
          "the job report prints 22.6, not 22.600000000000001")

    # ---- the client's errors ----
    out = cl.run("submit", job, "--rnus", "3")
    check(out.returncode == 2 and "did you mean --runs?" in out.stderr and
          len(out.stderr.splitlines()) == 1, "a mistyped flag: one line with a suggestion: %s" % out.stderr)
    out = cl.run("submit", cl.path("no-such-job.json"))
    check(out.returncode == 2 and "cannot read the job file" in out.stderr and "No such file" in out.stderr
          and "line -1" not in out.stderr, "a missing job file says so: %s" % out.stderr)
    out = cl.run("list", env_token=False)
    check(out.returncode == 2 and "none was given" in out.stderr, "no token: %s" % out.stderr)
    out = cl.run("list", env_token=False, extra_env={"SHADEBENCH_TOKEN": "wrong"})
    check(out.returncode == 2 and "refused the token from $SHADEBENCH_TOKEN" in out.stderr,
          "a wrong token is told apart from a missing one: %s" % out.stderr)
    out = cl.run("--token-file", cl.path("nope"), "list", env_token=False)
    check(out.returncode == 2 and "No such file" in out.stderr, "a missing token file says why")
    out = cl.run("info")
    check(out.returncode == 0 and "techniques (" in out.stdout and "effects (" in out.stdout and
          "limits:" in out.stdout and "--json" in out.stdout and len(out.stdout.splitlines()) < 40,
          "info prints a summary: %s" % out.stdout[:300])
    out = cl.run("info", "--json")
    check(out.returncode == 0 and json.loads(out.stdout).get("techniques"), "info --json: the raw answer")
finally:
    os.unlink(token_file)
    testlib.stop_and_check(d)
testlib.finish("e2e_verdicts")
