#!/usr/bin/env python3
"""How often does the timing gate cry wolf, and how often does it miss?

On one daemon, with busy-loop processes loading the CPU the whole time (as
on a shared CI box), this benchmark:
  1. finds a light count that makes the job about 10% slower, unless
     --slow-lights is given: forward's cost grows linearly with the lights
     (each fragment loops over them), so it measures the job against one
     with many more lights (`shadebench ab`, paired runs: a large ratio is
     measured precisely even on a noisy machine) and takes the extra lights
     that cost 10% from that slope, rounded up;
  2. takes a baseline of the unchanged job (`submit --runs N --out`);
  3. runs the gate --trials times on the unchanged job and --trials times on
     the slowed one (--allow-mismatch, since more lights is another spec),
     interleaved so that both see the same conditions over time;
     With --mode ab, step 2 is skipped and each gate is `shadebench ab`
     instead: the job against itself, or against the slowed job, in
     alternating runs, so that a drift of the machine between gates cannot
     pass for a change;
  4. reports the false-regression rate (unchanged job judged a regression)
     and the catch rate (slowed job judged a regression), with the
     inconclusive verdicts, the runs each gate used and the measured
     slowdowns.

    SHADEBENCHD=build/shadebenchd SHADEBENCH_CLIENT=build/shadebench bench/bench_gate.py

Standard library only. Writes every gate's files and a summary.json under
--out (default: a temporary folder, printed)."""

import argparse
import json
import math
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time

SHADEBENCHD = os.environ.get("SHADEBENCHD", "build/shadebenchd")
CLIENT = os.environ.get("SHADEBENCH_CLIENT", "build/shadebench")


def start_daemon(tmp):
    port_file = os.path.join(tmp, "port")
    log = open(os.path.join(tmp, "daemon.log"), "w")
    proc = subprocess.Popen([SHADEBENCHD, "--listen", "127.0.0.1:0", "--port-file", port_file,
                             "--state-dir", os.path.join(tmp, "state")], stdout=log,
                            stderr=subprocess.STDOUT)
    deadline = time.time() + 60
    while not os.path.exists(port_file):
        if proc.poll() is not None or time.time() > deadline:
            raise RuntimeError("shadebenchd did not start (see %s/daemon.log)" % tmp)
        time.sleep(0.05)
    time.sleep(0.1)
    with open(port_file) as f:
        return proc, "http://127.0.0.1:%d" % int(f.read())


def client(server, *args):
    return subprocess.run([CLIENT, "--server", server, "--quiet"] + [str(a) for a in args],
                          capture_output=True, text=True)


def write(path, obj):
    with open(path, "w") as f:
        json.dump(obj, f)
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=20)
    ap.add_argument("--runs", type=int, default=5, help="runs per side (the gate's default)")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--lights", type=int, default=10)
    ap.add_argument("--slow-lights", type=int, default=0,
                    help="light count of the slowed job (default: the smallest found ~10%% slower)")
    ap.add_argument("--target", type=float, default=0.10, help="slowdown to calibrate for")
    ap.add_argument("--calibration-pairs", type=int, default=10)
    ap.add_argument("--load", type=int, default=1, help="busy-loop processes (default 1)")
    ap.add_argument("--mode", choices=("baseline", "ab"), default="baseline",
                    help="baseline: submit --baseline against one baseline taken first; "
                         "ab: shadebench ab, the job against itself or the slowed job, "
                         "alternating runs within each gate")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()

    # SIGTERM ends the benchmark like ^C: the daemon and the loads stop too.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(3))
    out = a.out or tempfile.mkdtemp(prefix="bench-gate-")
    os.makedirs(out, exist_ok=True)
    job = {"technique": "forward", "frames": a.frames, "warmup_frames": 10,
           "scene": {"width": a.width, "height": a.height, "dynamic": True, "lights": a.lights}}
    loads = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(a.load)]
    daemon, server = start_daemon(out)
    t0 = time.time()
    try:
        base_file = write(os.path.join(out, "job.json"), job)

        def slowed(n):
            return write(os.path.join(out, "job-%d-lights.json" % n),
                         dict(job, scene=dict(job["scene"], lights=n)))

        # 1. The slowdown: the cost of a light from a large, precisely
        # measured ratio, then the lights that cost the target share.
        calibration = []
        if a.slow_lights:
            slow_lights = a.slow_lights
        else:
            far = a.lights * 4
            ab_dir = os.path.join(out, "ab-%d" % far)
            client(server, "ab", base_file, slowed(far), "--runs", a.calibration_pairs,
                   "--max-reruns", 0, "--max-slowdown", "10000%", "--out", ab_dir)
            with open(os.path.join(ab_dir, "ab.json")) as f:
                ab = json.load(f)
            per_light = (ab["ratio"] - 1) / (far - a.lights)
            slow_lights = a.lights + max(1, math.ceil(a.target / per_light)) if per_light > 0 else far
            calibration.append({"lights": far, "ratio": ab["ratio"], "ci": [ab["ci_low"], ab["ci_high"]],
                                "per_light": per_light})
            print("calibration: %d against %d lights: B/A = %.3f [%.3f, %.3f], %.2f%% a light: "
                  "%d lights for %+.0f%%" % (far, a.lights, ab["ratio"], ab["ci_low"], ab["ci_high"],
                                             100 * per_light, slow_lights, 100 * a.target), flush=True)
        slow_file = slowed(slow_lights)
        # The slowdown itself, paired, for the report.
        ab_dir = os.path.join(out, "ab-%d" % slow_lights)
        client(server, "ab", base_file, slow_file, "--runs", a.calibration_pairs, "--max-reruns", 0,
               "--max-slowdown", "10000%", "--out", ab_dir)
        with open(os.path.join(ab_dir, "ab.json")) as f:
            ab = json.load(f)
        slow_ratio = ab["ratio"]
        calibration.append({"lights": slow_lights, "ratio": ab["ratio"], "ci": [ab["ci_low"], ab["ci_high"]]})
        print("slowed job: %d lights: B/A = %.3f [%.3f, %.3f]" % (slow_lights, ab["ratio"], ab["ci_low"],
                                                                  ab["ci_high"]), flush=True)

        # 2. The baseline (ab measures its own, alternately, in every gate).
        baseline = None
        if a.mode == "baseline":
            base_dir = os.path.join(out, "baseline")
            r = client(server, "submit", base_file, "--wait", "--runs", a.runs, "--out", base_dir)
            if r.returncode != 0:
                raise RuntimeError("baseline failed: %s" % r.stderr[-500:])
            baseline = os.path.join(base_dir, "result.json")

        # 3. The gates, interleaved.
        results = {"unchanged": [], "slowed": []}
        for i in range(a.trials):
            for kind, path, extra in (("unchanged", base_file, []),
                                      ("slowed", slow_file, ["--allow-mismatch"])):
                gate_dir = os.path.join(out, "%s-%02d" % (kind, i + 1))
                start = time.time()
                try:
                    if a.mode == "ab":
                        r = client(server, "ab", base_file, path, "--runs", a.runs, "--out", gate_dir)
                        with open(os.path.join(gate_dir, "ab.json")) as f:
                            g = json.load(f)
                        # A pair is two runs, noisy together.
                        runs = [p for p in g["runs"] for _ in (0, 1)]
                    else:
                        r = client(server, "submit", path, "--wait", "--baseline", baseline, "--out",
                                   gate_dir, *extra)
                        with open(os.path.join(gate_dir, "gate.json")) as f:
                            g = json.load(f)
                        with open(os.path.join(gate_dir, "result.json")) as f:
                            runs = json.load(f)["gate_runs"]
                except (OSError, ValueError, KeyError):
                    g, runs = {"outcome": "error", "why": r.stderr[-300:]}, []
                took = time.time() - start
                rec = {"rc": r.returncode, "outcome": g["outcome"], "ratio": g.get("ratio"),
                       "ci": [g.get("ci_low"), g.get("ci_high")], "runs": len(runs),
                       "noisy": sum(1 for x in runs if x.get("noisy")), "seconds": took,
                       "why": g.get("why")}
                results[kind].append(rec)
                print("%-9s %2d: %-12s ratio %s, %d runs (%d noisy), %.0f s" % (
                    kind, i + 1, rec["outcome"], "%.3f" % rec["ratio"] if rec["ratio"] else "-",
                    rec["runs"], rec["noisy"], took), flush=True)
    finally:
        daemon.send_signal(signal.SIGTERM)
        daemon.wait(timeout=60)
        for p in loads:
            p.kill()
            p.wait()

    def count(kind, outcome):
        return sum(1 for x in results[kind] if x["outcome"] == outcome)

    n = a.trials
    summary = {
        "trials": n, "runs": a.runs, "mode": a.mode, "job": job, "slow_lights": slow_lights,
        "slowdown_paired": slow_ratio - 1, "calibration": calibration,
        "slowdown_in_gates": statistics.median(x["ratio"] for x in results["slowed"] if x["ratio"]) - 1,
        "false_regressions": count("unchanged", "regression"),
        "unchanged_pass": count("unchanged", "pass"),
        "unchanged_inconclusive": count("unchanged", "inconclusive"),
        "caught": count("slowed", "regression"),
        "slowed_pass": count("slowed", "pass"),
        "slowed_inconclusive": count("slowed", "inconclusive"),
        "errors": count("unchanged", "error") + count("slowed", "error"),
        "mean_runs": statistics.mean(x["runs"] for k in results for x in results[k]),
        "mean_gate_s": statistics.mean(x["seconds"] for k in results for x in results[k]),
        "load_processes": a.load, "minutes": (time.time() - t0) / 60, "results": results,
    }
    write(os.path.join(out, "summary.json"), summary)
    print()
    print("| measurement | value |")
    print("|---|---|")
    print("| gate | %s |" % ("shadebench ab: A and B alternately in each gate" if a.mode == "ab"
                             else "submit --baseline: one baseline taken before the trials"))
    print("| job | forward, %dx%d, %d frames, %d lights; %d busy-loop process(es) |" % (
        a.width, a.height, a.frames, a.lights, a.load))
    print("| slowed job | %d lights: %+.1f%% (paired, ab), %+.1f%% (median over its gates) |" % (
        slow_lights, 100 * summary["slowdown_paired"], 100 * summary["slowdown_in_gates"]))
    print("| unchanged job: false regressions | %d of %d (pass %d, inconclusive %d) |" % (
        summary["false_regressions"], n, summary["unchanged_pass"], summary["unchanged_inconclusive"]))
    print("| slowed job: caught | %d of %d (pass %d, inconclusive %d) |" % (
        summary["caught"], n, summary["slowed_pass"], summary["slowed_inconclusive"]))
    print("| runs per gate (mean), seconds per gate (mean) | %.1f, %.0f |" % (
        summary["mean_runs"], summary["mean_gate_s"]))
    print("| errors | %d |" % summary["errors"])
    print("\nfiles in %s (%.0f minutes)" % (out, summary["minutes"]))
    ok = summary["false_regressions"] <= max(1, n // 20) and summary["caught"] >= n - max(1, n // 20)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
