"""shadebench ab end to end: forward against unlit on one daemon, run in
alternating pairs, gives B/A with an interval that contains the ratio of
separate runs of the same jobs; the same job on two daemons (--server-b)
pairs across them; JUnit and exit codes as for the gate.

The forward/unlit ratio itself moves with the machine's load on llvmpipe
(forward's rasterization is spread over threads that compete with the
neighbours; unlit's vertex work is not), so the separate runs bracket the
ab run in time (half before, half after, in A B B A order) and the
interval is taken at 99%: the check is that ab's interval is honest, not
that the load stands still.

Jobs stay tiny (96x72, spheres of 8 segments: about 1 ms a frame unlit, 4
forward with 30 lights): ab's statistics are under test, not the renderer.
100 frames keep each run's timed region (0.1 s unlit) long enough for the
daemon's share of CPU taken by other processes, which marks noisy pairs, to
be measured rather than rounded to the kernel's ticks."""

import json
import os
import statistics

import testlib
from testlib import check
from clientlib import Client, junit_cases

testlib.skip_without_egl()
# Enough lights that forward costs several times unlit (4 times here): the
# verdict must not hang on noise from a busy machine.
SCENE = {"width": 96, "height": 72, "dynamic": True, "lights": 30, "sphere_segments": 8}
FORWARD = {"technique": "forward", "frames": 100, "warmup_frames": 3, "scene": SCENE}
UNLIT = dict(FORWARD, technique="unlit")

d = testlib.Daemon()
d2 = None
cl = Client(d)
try:
    fa, fb = cl.write("forward", FORWARD), cl.write("unlit", UNLIT)
    separate = {"forward": [], "unlit": []}

    def separate_runs(order):
        for name in order:
            r = d.run(FORWARD if name == "forward" else UNLIT)
            check(r["status"] == "done", "%s run done" % name)
            separate[name].append(r["result"]["frame_ms"]["median"])

    separate_runs(("forward", "unlit", "unlit", "forward"))
    outdir, junit = cl.path("ab"), cl.path("ab.xml")
    out = cl.run("ab", fa, fb, "--runs", "6", "--max-reruns", "6", "--confidence", "99%",
                 "--noise-tolerance", "30%",
                 "--out", outdir, "--junit", junit)
    check(out.returncode == 0, "unlit is not slower than forward: exit 0: %s" % out.stderr[-600:])
    with open(os.path.join(outdir, "ab.json")) as f:
        ab = json.load(f)
    pairs = [p for p in ab["runs"] if not p["noisy"]]
    check(ab["clean_pairs"] >= 6 and len(pairs) == ab["clean_pairs"] and ab["pairs"] >= ab["clean_pairs"],
          "at least 6 clean pairs: %s" % ab["clean_pairs"])
    # Alternation: A before B in even pairs, B before A in odd ones (ids
    # sort in submission order).
    order = [(p["a"] < p["b"]) for p in ab["runs"]]
    check(order == [i % 2 == 0 for i in range(len(order))], "pairs alternate A B, B A, ...: %s" % order)
    lo, ratio, hi = ab["ci_low"], ab["ratio"], ab["ci_high"]
    check(0 < lo < ratio < hi and ratio < 1, "B/A = %.3f in [%.3f, %.3f], below 1: unlit is cheaper" % (ratio, lo, hi))
    gm = statistics.geometric_mean([p["b_ms"] / p["a_ms"] for p in pairs])
    check(ab["bounded"] or abs(gm - ratio) < 1e-6 * ratio,
          "the ratio is the geometric mean of the clean pairs' ratios (unless noisy pairs decided, bounded)")
    _, cases = junit_cases(junit)
    abcase = [c for n, c in cases.items() if "B/A" in n]
    check(len(abcase) == 1 and abs(float(abcase[0][2]["ratio"]) - ratio) < 1e-5 * ratio and
          abcase[0][0] is None and abcase[0][2]["confidence"] == "0.99",
          "JUnit has the ratio with its interval: %s" % abcase)
    check(len(cases) == 3 and all(not n.startswith("2026") for n in cases), "a job case per side, named by content")
    for side in ("A", "B"):
        check(len(os.listdir(os.path.join(outdir, side, "runs"))) == len(ab["runs"]), "%s's runs are kept" % side)

    # Separate runs, each a job, four before ab and four after: the ratios
    # they admit (any unlit run over any forward run) meet ab's interval.
    # Not their median ratio inside it: the load moves between the separate
    # runs and ab's, and a 99% interval is not meant to cover that drift.
    separate_runs(("unlit", "forward", "forward", "unlit"))
    sep = statistics.median(separate["unlit"]) / statistics.median(separate["forward"])
    span = (min(separate["unlit"]) / max(separate["forward"]), max(separate["unlit"]) / min(separate["forward"]))
    check(span[0] <= hi and lo <= span[1] and span[1] < 1,
          "separate runs' ratios %.3f to %.3f (median %.3f) meet ab's interval [%.3f, %.3f]"
          % (span[0], span[1], sep, lo, hi))

    # B slower than A beyond the allowance: exit 1, like a regression. The
    # same two jobs the other way round: B (forward) costs 4 times A. Noise
    # marking off, as in e2e_gate: this checks detection, and at load
    # average 8 every pair made to confirm the slowdown was marked noisy,
    # which left it "could not be confirmed" (exit 0); the first ab above
    # checks the noise marking.
    out = cl.run("ab", fb, fa, "--runs", "3", "--max-reruns", "6", "--max-slowdown", "5%",
                 "--noise-tolerance", "off")
    check(out.returncode == 1 and "B SLOWER" in out.stderr,
          "forward with 30 lights as B is slower than unlit: exit 1: %s" % out.stderr[-400:])

    # The same job on two daemons.
    d2 = testlib.Daemon()
    out = cl.run("ab", cl.write("small", dict(FORWARD, frames=20)), "--server-b", d2.base, "--runs", "3",
                 "--max-reruns", "0",
                 "--max-slowdown", "400%", "--out", cl.path("two"))
    check(out.returncode == 0, "one job on two daemons: %s" % out.stderr[-400:])
    with open(cl.path("two", "ab.json")) as f:
        two = json.load(f)
    b_ids = {p["b"] for p in two["runs"]}
    on_b = {j["id"] for j in d2.json("GET", "/v1/jobs")[1]["jobs"]}
    check(two["server_b"] == d2.base and b_ids <= on_b and len(b_ids) == 3, "B's runs ran on the second daemon")
    check(0.2 < two["ratio"] < 5, "the same job gives a ratio near 1: %.3f" % two["ratio"])
    check(cl.run("ab", fa).returncode == 2, "ab with one job file needs --server-b")
    check(cl.run("ab", fa, fb, "--server-b", d2.base).returncode == 2, "two files and --server-b is refused")
finally:
    if d2:
        testlib.stop_and_check(d2)
    testlib.stop_and_check(d)
testlib.finish("e2e_ab")
