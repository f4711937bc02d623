#!/usr/bin/env python3
"""Metrics benchmark: each metric on a 1080x720 pair (forward and OSL renders
of the thesis scene), scikit-image's SSIM on the same pair in the same run,
and the time it took to render that pair, all side by side.

  SHADEBENCHD=build/shadebenchd SHADEBENCH_COMPARE=build/shadebench-compare bench/bench_metrics.py
      [--repeat N] [--render-repeat N]

Interleaved: each of the --repeat rounds runs shadebench's four metrics,
its SSIM alone and scikit-image's two SSIMs in turn; the pair is rendered
--render-repeat times (forward, OSL, forward, OSL, ...) before them, and
its time is the sum of the two techniques' medians of the job medians. The
run's commit, command, date and load are printed.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

try:
    import numpy as np
    from PIL import Image
    from skimage.metrics import structural_similarity
except ImportError:
    if sys.executable != "/usr/bin/python3" and os.path.exists("/usr/bin/python3"):
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    sys.exit("needs numpy, PIL and scikit-image (Debian: python3-skimage python3-pil)")

ap = argparse.ArgumentParser()
ap.add_argument("--repeat", type=int, default=7)
ap.add_argument("--render-repeat", type=int, default=3)
ap.add_argument("--width", type=int, default=1080)
ap.add_argument("--height", type=int, default=720)
args = ap.parse_args()
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchrun  # noqa: E402
bench = benchrun.Run()
bench.start()
print()
shadebenchd = os.environ.get("SHADEBENCHD", "build/shadebenchd")
compare = os.environ.get("SHADEBENCH_COMPARE", "build/shadebench-compare")

with tempfile.TemporaryDirectory() as tmp:
    frames = {}
    renders = {"forward": [], "osl": []}
    for rep in range(args.render_repeat):
        for tech in ("forward", "osl"):
            job = {"technique": tech, "frames": 30, "warmup_frames": 5, "capture_interval": 30,
                   "async_distance": 20, "scene": {"dynamic": True, "width": args.width, "height": args.height},
                   "osl": {"resolution": "auto"}}
            path = os.path.join(tmp, tech + ".json")
            with open(path, "w") as f:
                json.dump(job, f)
            out = os.path.join(tmp, "%s-%d" % (tech, rep))
            subprocess.run([shadebenchd, "--once", path, "--out", out], check=True, capture_output=True)
            with open(os.path.join(out, "result.json")) as f:
                renders[tech].append(json.load(f))
            print("  [%d/%d] render %-8s frame_ms median %.1f" % (rep + 1, args.render_repeat, tech,
                                                               renders[tech][-1]["frame_ms"]["median"]),
                  flush=True)
            frames.setdefault(tech, os.path.join(out, "frame-000030.png"))
    render_ms = {t: statistics.median(r["frame_ms"]["median"] for r in rs) for t, rs in renders.items()}

    ours = {m: [] for m in ("ssim", "ssim-alone", "pdiff", "psnr", "flip", "all")}
    sk_luma, sk_rgb = [], []
    a = np.asarray(Image.open(frames["forward"]).convert("RGB")).astype(np.float64)
    b = np.asarray(Image.open(frames["osl"]).convert("RGB")).astype(np.float64)
    ya = 0.299 * a[..., 0] + 0.587 * a[..., 1] + 0.114 * a[..., 2]
    yb = 0.299 * b[..., 0] + 0.587 * b[..., 1] + 0.114 * b[..., 2]
    kw = dict(gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=255)
    for _ in range(args.repeat):
        res = json.loads(subprocess.run([compare, frames["forward"], frames["osl"]], check=False,
                                        capture_output=True, text=True).stdout)
        for m in ("ssim", "pdiff", "psnr", "flip"):
            ours[m].append(res["timing_ms"][m])
        ours["all"].append(res["timing_ms"]["total"])
        # SSIM on its own, as scikit-image runs below.
        alone = json.loads(subprocess.run([compare, frames["forward"], frames["osl"], "--metrics", "ssim"],
                                          check=False, capture_output=True, text=True).stdout)
        ours["ssim-alone"].append(alone["timing_ms"]["ssim"])
        t = time.perf_counter()
        structural_similarity(ya, yb, **kw)
        sk_luma.append((time.perf_counter() - t) * 1e3)
        t = time.perf_counter()
        structural_similarity(a, b, channel_axis=2, **kw)
        sk_rgb.append((time.perf_counter() - t) * 1e3)

bench.end(renders["forward"] + renders["osl"])
med = {m: statistics.median(v) for m, v in ours.items()}
pair_ms = render_ms["forward"] + render_ms["osl"]
print("\npair: %dx%d forward and OSL renders (%d of each, interleaved); metrics: medians of %d "
      "interleaved runs\n" % (args.width, args.height, args.render_repeat, args.repeat))
print("| measurement | ms |")
print("|---|---|")
notes = {"ssim": " (luma + R, G, B), beside the others", "ssim-alone": " (luma + R, G, B), alone",
         "all": " four metrics, wall (FLIP on a second thread)"}
for m in ("ssim-alone", "ssim", "pdiff", "psnr", "flip", "all"):
    print("| shadebench %s%s | %.1f |" % (m, notes.get(m, ""), med[m]))
print("| scikit-image SSIM, luma | %.1f |" % statistics.median(sk_luma))
print("| scikit-image SSIM, R G B (channel_axis) | %.1f |" % statistics.median(sk_rgb))
print("| rendering the pair (frame_ms medians, forward + OSL) | %.1f |" % pair_ms)
sk_both = statistics.median(sk_luma) + statistics.median(sk_rgb)
print("\nSSIM speed-up over scikit-image (same outputs: luma and RGB, each alone): %.1fx"
      % (sk_both / med["ssim-alone"]))
print("all four metrics / rendering the pair: %.2f" % (med["all"] / pair_ms))
