#!/usr/bin/env python3
"""Post-effect benchmark, in one run on one daemon, interleaved over repeats:

1. bloom: separable (2 x (2r+1) taps) against 2d ((2r+1)^2 taps) at radius
   2, 4, 8 and 16; seed 001 measured 2.5 times at 5x5 (r = 2), and the
   arithmetic limit of the ratio is (2r+1)/2;
2. SSAO: cost against sample count (4 to 64), with its quality as the SSIM
   against 64 samples (reference_look renders the 64-sample image);
3. the whole chain (bloom, toon with Sobel outlines, SSAO, ACES) as a share
   of each technique's frame.

  bench/bench_post.py [--frames N] [--warmup N] [--repeat R] [--width W --height H] [--json FILE]

Effect costs are the medians of the effect passes' GL_TIME_ELAPSED
(gpu_sections_ms): on llvmpipe that covers rasterization, which is all a
full-screen pass does, so they compare there too. frame_ms is reported
beside them."""

import argparse
import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "e2e"))
import testlib  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--frames", type=int, default=10)
ap.add_argument("--warmup", type=int, default=2)
ap.add_argument("--repeat", type=int, default=2)
ap.add_argument("--width", type=int, default=480)
ap.add_argument("--height", type=int, default=320)
ap.add_argument("--json", help="write every result here")
args = ap.parse_args()

RADII = (2, 4, 8, 16)
SAMPLES = (4, 8, 16, 32, 64)
TECHNIQUES = (("forward", {}), ("unlit", {}), ("osl-auto", {"technique": "osl", "osl": {"resolution": "auto"}}))
CHAIN = {"post": [{"bloom": {"radius": 4}}, {"toon": {"edges": "sobel"}}, {"ssao": {"samples": 16}}],
         "tonemap": "aces"}


def base_job(**kw):
    job = {"technique": "forward", "frames": args.frames, "warmup_frames": args.warmup,
           "capture_interval": 0,
           "scene": {"dynamic": True, "width": args.width, "height": args.height}}
    job.update(kw)
    return job


CONFIGS = []
for r in RADII:
    for kernel in ("separable", "2d"):
        CONFIGS.append(("bloom-%s-r%d" % (kernel, r),
                        base_job(look={"post": [{"bloom": {"kernel": kernel, "radius": r, "threshold": 0}}]})))
for n in SAMPLES:
    CONFIGS.append(("ssao-%d" % n,
                    base_job(look={"post": [{"ssao": {"samples": n}}]}, capture_interval=args.frames,
                             reference="forward", metrics=["ssim"],
                             reference_look={"post": [{"ssao": {"samples": 64}}]})))
for name, extra in TECHNIQUES:
    CONFIGS.append(("%s-plain" % name, base_job(**extra)))
    CONFIGS.append(("%s-chain" % name, base_job(look=CHAIN, **extra)))


def med(values):
    return statistics.median(values) if values else float("nan")


def section(r, prefix):
    """Sum of the median GPU ms of the passes whose names start with prefix."""
    return sum(v["median"] for k, v in r["gpu_sections_ms"].items() if k.startswith(prefix))


d = testlib.Daemon()
results = {name: [] for name, _ in CONFIGS}
try:
    info = d.json("GET", "/v1/info")[1]["device"]
    print("device: %s | %s" % (info["gl_renderer"], info["gl_version"]))
    print("scene: grid %dx%d, moving lights, %d timed frames after %d warm-up, %d repeats\n"
          % (args.width, args.height, args.frames, args.warmup, args.repeat))
    t_start, load0 = time.time(), os.getloadavg()[0]
    for rep in range(args.repeat):
        for name, job in CONFIGS:
            t0 = time.time()
            done = d.wait(d.submit(job), timeout=3600)
            if done.get("status") != "done":
                sys.exit("%s failed: %s" % (name, done.get("error")))
            r = done["result"]
            results[name].append(r)
            print("  [%d/%d] %-22s frame %9.2f ms  gpu %9.2f ms  (%.0f s)"
                  % (rep + 1, args.repeat, name, r["frame_ms"]["median"], r["gpu_ms"]["median"],
                     time.time() - t0), flush=True)
    print("\n(%.0f s in all; load average %.2f before, %.2f after, on %d cores)\n"
          % (time.time() - t_start, load0, os.getloadavg()[0], os.cpu_count()))

    def m(name, f):
        return med([f(r) for r in results[name]])

    def paired(a, b, f):
        """Median over repeats of f(b) / f(a), each pair run side by side."""
        return med([f(y) / f(x) for x, y in zip(results[a], results[b]) if f(x) > 0])

    print("## Bloom: separable against 2d (medians over repeats of job medians, ms; ratios "
          "paired within each repeat)\n")
    print("| radius | taps 2d / separable | sep. blur | 2d blur | blur ratio 2d/sep. | "
          "arithmetic limit (2r+1)/2 | whole bloom ratio | frame_ms sep. | frame_ms 2d | frame ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in RADII:
        sep, two = "bloom-separable-r%d" % r, "bloom-2d-r%d" % r
        bs, b2 = m(sep, lambda x: section(x, "bloom.blur")), m(two, lambda x: section(x, "bloom.blur"))
        ws, w2 = m(sep, lambda x: section(x, "bloom.")), m(two, lambda x: section(x, "bloom."))
        fs, f2 = m(sep, lambda x: x["frame_ms"]["median"]), m(two, lambda x: x["frame_ms"]["median"])
        taps = (2 * r + 1)
        ratio = paired(sep, two, lambda x: section(x, "bloom.blur"))
        whole = paired(sep, two, lambda x: section(x, "bloom."))
        frame = paired(sep, two, lambda x: x["frame_ms"]["median"])
        print("| %d (%dx%d) | %d / %d | %.2f | %.2f | %.2f | %.1f | %.2f | %.2f | %.2f | %.2f |"
              % (r, taps, taps, taps * taps, 2 * taps, bs, b2, ratio, taps / 2.0, whole, fs, f2,
                 frame))

    print("\n## SSAO: cost and quality against samples\n")
    print("| samples | ssao.ao ms | ssao.blur ms | both | frame_ms | SSIM against 64 samples |")
    print("|---|---|---|---|---|---|")
    for n in SAMPLES:
        name = "ssao-%d" % n
        ao, bl = m(name, lambda x: section(x, "ssao.ao")), m(name, lambda x: section(x, "ssao.blur"))
        fr = m(name, lambda x: x["frame_ms"]["median"])
        ssim = m(name, lambda x: x["quality"]["worst_ssim"]["value"]) if "quality" in results[name][0] else float("nan")
        print("| %d | %.2f | %.2f | %.2f | %.2f | %.5f |" % (n, ao, bl, ao + bl, fr, ssim))

    print("\n## The whole chain (bloom r4, toon Sobel, SSAO 16, ACES) against each technique's frame\n")
    print("| technique | frame_ms plain | frame_ms chain | chain share of frame_ms | technique gpu ms | "
          "post passes gpu ms | post share of gpu_ms | per effect gpu ms (bloom, toon, ssao) |")
    print("|---|---|---|---|---|---|---|---|")
    for name, _ in TECHNIQUES:
        plain, chain = name + "-plain", name + "-chain"
        fp, fc = m(plain, lambda x: x["frame_ms"]["median"]), m(chain, lambda x: x["frame_ms"]["median"])
        post = m(chain, lambda x: section(x, "bloom.") + section(x, "toon.") + section(x, "ssao."))
        gpu = m(chain, lambda x: x["gpu_ms"]["median"])
        tech = m(chain, lambda x: x["gpu_ms"]["median"] - section(x, "bloom.") - section(x, "toon.")
                 - section(x, "ssao.") - section(x, "resolve"))
        per = [m(chain, lambda x, p=p: section(x, p)) for p in ("bloom.", "toon.", "ssao.")]
        print("| %s | %.2f | %.2f | %.1f %% | %.2f | %.2f | %.1f %% | %.2f, %.2f, %.2f |"
              % (name, fp, fc, 100.0 * (fc - fp) / fc, tech, post, 100.0 * post / gpu, *per))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)
finally:
    d.stop()
    d.cleanup()
