#!/usr/bin/env python3
"""Issue 25's Done-when, as written: the job

  {"technique":"osl","async_distance":20,"reference":"forward",
   "scene":{"preset":"grid","dynamic":true,"width":1080,"height":720}}

(no OSL options: the defaults) against forward on the same scene, in
interleaved pairs on one daemon. Prints per pair both frame_ms medians and
cpu_work_ms (the daemon's CPU time per timed frame), the ratio, the OSL
job's worst and mean SSIM against forward and its texels per pixel; then
the medians of the ratios.

  bench/bench_osl_done.py [--rounds N] [--frames N] [--warmup N]

--frames and --warmup default to the job's defaults (left out of the job)."""

import statistics
import sys

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--rounds", type=int, default=2)
ap.add_argument("--frames", type=int)
ap.add_argument("--warmup", type=int)
args = ap.parse_args()

SCENE = {"preset": "grid", "dynamic": True, "width": 1080, "height": 720}
OSL = {"technique": "osl", "async_distance": 20, "reference": "forward", "scene": SCENE}
FWD = {"technique": "forward", "scene": SCENE}
for j in (OSL, FWD):
    if args.frames:
        j["frames"] = args.frames
    if args.warmup is not None:
        j["warmup_frames"] = args.warmup

bench = benchrun.Run()
bench.start()
d = testlib.Daemon()
results, ratios, cpu_ratios = [], [], []
try:
    for k in range(args.rounds):
        # Alternate which runs first, so that a trend in load spreads evenly.
        order = [FWD, OSL] if k % 2 == 0 else [OSL, FWD]
        got = {}
        for job in order:
            done = d.run(job)
            if done.get("status") != "done":
                sys.exit("bench_osl_done: %s failed: %s" % (job["technique"], done.get("error")))
            got[job["technique"]] = done["result"]
            results.append(done["result"])
        f, o = got["forward"], got["osl"]
        ratio = o["frame_ms"]["median"] / f["frame_ms"]["median"]
        cpu = benchrun.cpu_work_ms(o) / benchrun.cpu_work_ms(f)
        ratios.append(ratio)
        cpu_ratios.append(cpu)
        q = o.get("quality", {})
        vis = o.get("osl", {}).get("visibility", {})
        print("round %d: forward %.2f ms (cpu_work %.1f), osl %.2f ms (cpu_work %.1f): x%.3f "
              "(cpu_work x%.3f); worst SSIM %s over %s captures; %.3f texels per pixel; "
              "stale blocks %s" % (k + 1, f["frame_ms"]["median"], benchrun.cpu_work_ms(f),
                                   o["frame_ms"]["median"], benchrun.cpu_work_ms(o), ratio, cpu,
                                   q.get("worst_ssim", {}).get("value"), q.get("captures_compared"),
                                   vis.get("texels_per_pixel", 0), vis.get("stale_blocks")),
              flush=True)
finally:
    testlib.stop_and_check(d)
print("\nosl / forward, median of %d rounds: frame_ms x%.3f, cpu_work_ms x%.3f"
      % (args.rounds, statistics.median(ratios), statistics.median(cpu_ratios)))
bench.end(results)
