#!/usr/bin/env python3
"""osl.change_threshold against what it saves and what it costs in
accuracy (issue 25): OSL at its defaults on the thesis grid with moving
lights at async distance 20, at each threshold, against forward (reference:
forward, captured at the last frame). Prints texels shaded per frame, the
object reshades the bound let go against those the schedule asked for, the
staleness of the blocks read (median/p95/max frames since the lights of
their shading; the run's length caps it) and the worst SSIM.

  bench/bench_osl_threshold.py [--thresholds 0,0.02,0.1,0.3,1] [--frames N]
      [--warmup N] [--width W --height H]"""

import sys

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--thresholds", default="0,0.02,0.1,0.3,1")
ap.add_argument("--frames", type=int, default=10)
ap.add_argument("--warmup", type=int, default=3)
ap.add_argument("--width", type=int, default=480)
ap.add_argument("--height", type=int, default=320)
args = ap.parse_args()

bench = benchrun.Run()
bench.start()
d = testlib.Daemon()
results = []
try:
    print("%-9s %12s %14s %12s %10s" % ("threshold", "texels/frame", "saved/due", "age m/95/mx",
                                         "worst SSIM"))
    for t in [float(x) for x in args.thresholds.split(",")]:
        done = d.run({"technique": "osl", "frames": args.frames, "warmup_frames": args.warmup,
                      "capture_interval": args.frames, "async_distance": 20, "reference": "forward",
                      "osl": {"change_threshold": t},
                      "scene": {"preset": "grid", "dynamic": True, "width": args.width,
                                "height": args.height}})
        if done.get("status") != "done":
            sys.exit("bench_osl_threshold: %g failed: %s" % (t, done.get("error")))
        r = done["result"]
        results.append(r)
        o, ch = r["osl"], r["osl"].get("change", {})
        st = o["staleness"]
        print("%-9g %12.0f %14s %12s %10.5f" % (
            t, o["texels_shaded_per_frame"]["mean"],
            "%.1f/%.1f" % (ch["reshades_saved_per_frame"], ch["reshades_due_per_frame"]) if ch else "-",
            "%d/%d/%d" % (st["median"], st["p95"], st["max"]), r["quality"]["worst_ssim"]["value"]),
            flush=True)
finally:
    testlib.stop_and_check(d)
bench.end(results)
