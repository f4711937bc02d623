#!/usr/bin/env python3
"""Measurement integrity: does a job's frame time move because of the daemon's
own bookkeeping? Job B (a 480x320 forward job) is timed right behind job A,
whose reference render and metrics are heavy (1080x720, 8 captures scored
against forward with every metric), and alone; the two cases are interleaved
over --pairs rounds in one run, alternating which comes first, so that
machine noise spreads evenly over both.

  bench/bench_integrity.py [--pairs N] [--frames N] [--json FILE]

Reports the ratio median(B behind A) / median(B alone) of B's median
frame_ms (goal: at most 1.02), each round's figures, whether B's timed region
started after A finished (it must, by construction), and each B run's
result.interference, so a noisy round can be told from a real effect.
Needs a built daemon: SHADEBENCHD=build/shadebenchd."""

import datetime
import json
import statistics
import sys
import time

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--pairs", type=int, default=6, help="rounds of (B alone, A then B); at least 4")
ap.add_argument("--frames", type=int, default=40, help="B's timed frames")
ap.add_argument("--warmup", type=int, default=10)
ap.add_argument("--heavy-frames", type=int, default=40, help="A's timed frames (8 of them captured)")
ap.add_argument("--json", help="write every measurement here")
args = ap.parse_args()
if args.pairs < 4:
    sys.exit("--pairs must be at least 4")

HEAVY = {"technique": "forward", "frames": args.heavy_frames, "warmup_frames": 2,
         "capture_interval": args.heavy_frames // 8, "reference": "forward",
         "metrics": ["ssim", "pdiff", "psnr", "flip"],
         "scene": {"preset": "grid", "dynamic": True, "width": 1080, "height": 720}}
B = {"technique": "forward", "frames": args.frames, "warmup_frames": args.warmup,
     "scene": {"preset": "grid", "dynamic": True, "width": 480, "height": 320}}


def unix(iso):
    return datetime.datetime.strptime(iso, "%Y-%m-%dT%H:%M:%S.%fZ").replace(
        tzinfo=datetime.timezone.utc).timestamp()


def must_be_done(job, what):
    if job.get("status") != "done":
        sys.exit("%s %s: %s" % (what, job.get("status"), job.get("error")))
    return job


bench = benchrun.Run()
d = testlib.Daemon()
alone, behind, rounds = [], [], []
try:
    info = d.json("GET", "/v1/info")[1]["device"]
    print("device: %s | %s" % (info["gl_renderer"], info["gl_version"]))
    print("A: 1080x720, %d frames, %d captures against forward, all metrics; B: 480x320 forward, %d+%d frames\n"
          % (HEAVY["frames"], HEAVY["frames"] // HEAVY["capture_interval"], args.warmup, args.frames))
    bench.start()
    print()
    print("round  case     B frame_ms  B started after A finished  other_cpu  load1  noisy")
    for i in range(args.pairs):
        order = ("alone", "behind") if i % 2 == 0 else ("behind", "alone")
        for case in order:
            if case == "alone":
                b = must_be_done(d.run(B), "B alone")
                a = None
            else:
                a_id = d.submit(HEAVY)
                b_id = d.submit(B)  # queued while A renders: its metrics are pending when B is due
                a = must_be_done(d.wait(a_id), "A")
                b = must_be_done(d.wait(b_id), "B behind A")
            r = b["result"]
            interf = r.get("interference", {})
            after = None
            if a:  # B's timed region (or, from a daemon without it, B's start) after A finished
                after = interf.get("timed_start_unix", unix(b["started"])) >= unix(a["finished"])
            (alone if case == "alone" else behind).append(r["frame_ms"]["median"])
            rounds.append({"round": i + 1, "case": case, "frame_ms": r["frame_ms"]["median"],
                           "b_timed_after_a_finished": after, "interference": interf,
                           "a_metrics_s": a["result"]["quality"]["metrics_s"] if a else None})
            print("%5d  %-7s  %10.3f  %26s  %9.3f  %5.2f  %s"
                  % (i + 1, case, r["frame_ms"]["median"], "-" if after is None else after,
                     interf.get("other_cpu_share", float("nan")), (interf.get("loadavg_start") or [0])[0],
                     interf.get("noisy")), flush=True)
finally:
    d.stop()
    d.cleanup()
bench.end([{"interference": r["interference"]} for r in rounds if r["interference"]])

ratio = statistics.median(behind) / statistics.median(alone)
paired = [b / a for a, b in zip(alone, behind)]
noisy = sum(1 for r in rounds if r["interference"].get("noisy"))
print("\nB alone:    median of medians %.3f ms over %d runs" % (statistics.median(alone), len(alone)))
print("B behind A: median of medians %.3f ms over %d runs" % (statistics.median(behind), len(behind)))
print("ratio (behind / alone): %.4f   (goal <= 1.02); per round: %s"
      % (ratio, " ".join("%.3f" % p for p in paired)))
print("B's timed region after A finished in every pair: %s"
      % all(r["b_timed_after_a_finished"] for r in rounds if r["case"] == "behind"))
print("rounds flagged noisy by result.interference: %d of %d" % (noisy, len(rounds)))
if args.json:
    with open(args.json, "w") as f:
        json.dump({"ratio": ratio, "per_round": paired, "alone": alone, "behind": behind,
                   "rounds": rounds}, f, indent=2)
