#!/usr/bin/env python3
"""Post-effect benchmark, in one run on one daemon, interleaved over repeats:

1. bloom: separable (2 x (2r+1) taps) against 2d ((2r+1)^2 taps) at radius
   2, 4, 8 and 16; seed 001 measured 2.5 times at 5x5 (r = 2), and the
   arithmetic limit of the ratio is (2r+1)/2;
2. SSAO: cost against sample count (4 to 64), with its quality as the SSIM
   against 64 samples (reference_look renders the 64-sample image);
3. the whole chain (bloom, toon with Sobel outlines, SSAO, ACES) as a share
   of each technique's frame;
4. toon outlines against resolution: the same view at 1080x720 down to
   90x60, toon with Sobel outlines scored against the same ramp without
   outlines (reference_look), and the share of the objects' pixels the
   outlines blacken: outlines keep their width in pixels while the objects
   shrink, so at some resolution they cover the objects (where outlines
   break). Images, not times: run once, whatever --repeat says.

  bench/bench_post.py [--frames N] [--warmup N] [--repeat R] [--width W --height H]
                      [--only bloom,ssao,chain,toon] [--json FILE]

Effect costs are the medians of the effect passes' GL_TIME_ELAPSED
(gpu_sections_ms): on llvmpipe that covers rasterization, which is all a
full-screen pass does, so they compare there too. frame_ms is reported
beside them. The run's commit, command, date and load (/proc/loadavg at the
start and the end, and the jobs' result.interference) are printed first and
last."""

import os
import statistics
import sys
import time

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--frames", type=int, default=10)
ap.add_argument("--warmup", type=int, default=2)
ap.add_argument("--repeat", type=int, default=2)
ap.add_argument("--width", type=int, default=480)
ap.add_argument("--height", type=int, default=320)
ap.add_argument("--only", default="bloom,ssao,chain,toon",
                help="comma-separated parts to run: bloom, ssao, chain, toon")
ap.add_argument("--json", help="write every result here")
args = ap.parse_args()

RADII = (2, 4, 8, 16)
SAMPLES = (4, 8, 16, 32, 64)
TECHNIQUES = (("forward", {}), ("unlit", {}), ("osl-auto", {"technique": "osl", "osl": {"resolution": "auto"}}))
TOON_SIZES = ((1080, 720), (540, 360), (360, 240), (270, 180), (180, 120), (135, 90), (90, 60))
TOON_EDGES = (("sobel", {"edges": "sobel"}), ("depth_diff", {"edges": "depth_diff"}),
              ("depth_diff-t2", {"edges": "depth_diff", "thickness": 2}))
CHAIN = {"post": [{"bloom": {"radius": 4}}, {"toon": {"edges": "sobel"}}, {"ssao": {"samples": 16}}],
         "tonemap": "aces"}


def base_job(**kw):
    job = {"technique": "forward", "frames": args.frames, "warmup_frames": args.warmup,
           "capture_interval": 0,
           "scene": {"dynamic": True, "width": args.width, "height": args.height}}
    job.update(kw)
    return job


PARTS = set(args.only.split(","))
CONFIGS = []
for r in RADII if "bloom" in PARTS else ():
    for kernel in ("separable", "2d"):
        CONFIGS.append(("bloom-%s-r%d" % (kernel, r),
                        base_job(look={"post": [{"bloom": {"kernel": kernel, "radius": r, "threshold": 0}}]})))
for n in SAMPLES if "ssao" in PARTS else ():
    CONFIGS.append(("ssao-%d" % n,
                    base_job(look={"post": [{"ssao": {"samples": n}}]}, capture_interval=args.frames,
                             reference="forward", metrics=["ssim"],
                             reference_look={"post": [{"ssao": {"samples": 64}}]})))
for name, extra in TECHNIQUES if "chain" in PARTS else ():
    CONFIGS.append(("%s-plain" % name, base_job(**extra)))
    CONFIGS.append(("%s-chain" % name, base_job(look=CHAIN, **extra)))
TOON_CONFIGS = []
for w, h in TOON_SIZES if "toon" in PARTS else ():
    for label, toon in TOON_EDGES:
        job = base_job(look={"post": [{"toon": toon}]}, capture_interval=args.frames, reference="forward",
                       reference_look={"post": [{"toon": {"edges": "none"}}]}, metrics=["ssim", "flip"])
        job["scene"] = dict(job["scene"], width=w, height=h)
        TOON_CONFIGS.append(("toon-%s-%dx%d" % (label, w, h), job))


def med(values):
    return statistics.median(values) if values else float("nan")


def section(r, prefix):
    """Sum of the median GPU ms of the passes whose names start with prefix."""
    return sum(v["median"] for k, v in r["gpu_sections_ms"].items() if k.startswith(prefix))


def m(name, f):
    """Median over repeats of f(result)."""
    return med([f(r) for r in results[name]])


def paired(a, b, f):
    """Median over repeats of f(b) / f(a), each pair run side by side."""
    return med([f(y) / f(x) for x, y in zip(results[a], results[b]) if f(x) > 0])


def frame_ms(x):
    return x["frame_ms"]["median"]


def post_ms(x):
    return section(x, "bloom.") + section(x, "toon.") + section(x, "ssao.")


def bloom_table():
    print("## Bloom: separable against 2d (medians over repeats of job medians, ms; ratios "
          "paired within each repeat)\n")
    print("| radius | taps 2d / separable | sep. blur | 2d blur | blur ratio 2d/sep. | "
          "arithmetic limit (2r+1)/2 | whole bloom ratio | frame_ms sep. | frame_ms 2d | frame ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in RADII:
        sep, two = "bloom-separable-r%d" % r, "bloom-2d-r%d" % r
        taps = 2 * r + 1
        print("| %d (%dx%d) | %d / %d | %.2f | %.2f | %.2f | %.1f | %.2f | %.2f | %.2f | %.2f |"
              % (r, taps, taps, taps * taps, 2 * taps,
                 m(sep, lambda x: section(x, "bloom.blur")), m(two, lambda x: section(x, "bloom.blur")),
                 paired(sep, two, lambda x: section(x, "bloom.blur")), taps / 2.0,
                 paired(sep, two, lambda x: section(x, "bloom.")), m(sep, frame_ms), m(two, frame_ms),
                 paired(sep, two, frame_ms)))


def ssao_table():
    print("\n## SSAO: cost and quality against samples\n")
    print("| samples | ssao.ao ms | ssao.blur ms | both | frame_ms | SSIM against 64 samples |")
    print("|---|---|---|---|---|---|")
    for n in SAMPLES:
        name = "ssao-%d" % n
        ao, bl = m(name, lambda x: section(x, "ssao.ao")), m(name, lambda x: section(x, "ssao.blur"))
        ssim = m(name, lambda x: x.get("quality", {}).get("worst_ssim", {}).get("value", float("nan")))
        print("| %d | %.2f | %.2f | %.2f | %.2f | %.5f |" % (n, ao, bl, ao + bl, m(name, frame_ms), ssim))


def outline_share(d, done, tmp):
    """(outline pixels / object pixels, outline pixels / all pixels): an
    object pixel is lit (not black) in the image without outlines, an
    outline pixel is one of those that the outlines turn black."""
    cap = done["result"]["captures"][-1]
    paths = []
    for key in ("url", "reference_url"):
        path = os.path.join(tmp, key + ".png")
        if d.download(cap[key], path) != 200:
            sys.exit("cannot download %s" % cap[key])
        paths.append(path)
    w, h, toon = testlib.png_pixels(paths[0])
    _, _, plain = testlib.png_pixels(paths[1])
    objects = sum(1 for p in plain if any(p))
    outlined = sum(1 for a, b in zip(toon, plain) if any(b) and not any(a))
    return outlined / max(objects, 1), outlined / float(w * h)


def toon_table():
    print("\n## Toon outlines against resolution (grid, moving lights, frame %d; against the same ramp "
          "without outlines)\n" % args.frames)
    print("| size | outlines | objects' pixels outlined | image outlined | SSIM | FLIP mean |")
    print("|---|---|---|---|---|---|")
    for name, _ in TOON_CONFIGS:
        r = toon_results[name]
        q = r["result"].get("quality", {})
        print("| %s | %s | %.1f %% | %.1f %% | %.4f | %.4f |"
              % (name.rsplit("-", 1)[1], name[5:].rsplit("-", 1)[0], 100.0 * r["share"][0], 100.0 * r["share"][1],
                 q.get("worst_ssim", {}).get("value", float("nan")), q.get("worst_flip", {}).get("mean", float("nan"))))


def chain_table():
    print("\n## The whole chain (bloom r4, toon Sobel, SSAO 16, ACES) against each technique's frame\n")
    print("| technique | frame_ms plain | frame_ms chain | chain share of frame_ms (paired) | "
          "post passes gpu ms | post share of gpu_ms | per effect gpu ms (bloom, toon, ssao) |")
    print("|---|---|---|---|---|---|---|")
    for name, _ in TECHNIQUES:
        plain, chain = name + "-plain", name + "-chain"
        share = 1.0 - paired(chain, plain, frame_ms)  # (chain - plain) / chain
        per = [m(chain, lambda x, p=p: section(x, p)) for p in ("bloom.", "toon.", "ssao.")]
        print("| %s | %.2f | %.2f | %.1f %% | %.2f | %.1f %% | %.2f, %.2f, %.2f |"
              % (name, m(plain, frame_ms), m(chain, frame_ms), 100.0 * share, m(chain, post_ms),
                 100.0 * m(chain, lambda x: post_ms(x) / x["gpu_ms"]["median"]), *per))


bench = benchrun.Run()
d = testlib.Daemon()
results = {name: [] for name, _ in CONFIGS}
toon_results = {}
try:
    info = d.json("GET", "/v1/info")[1]["device"]
    print("device: %s | %s" % (info["gl_renderer"], info["gl_version"]))
    print("scene: grid %dx%d, moving lights, %d timed frames after %d warm-up, %d repeats\n"
          % (args.width, args.height, args.frames, args.warmup, args.repeat))
    bench.start()
    print()
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
    for name, job in TOON_CONFIGS:
        done = d.wait(d.submit(job), timeout=3600)
        if done.get("status") != "done":
            sys.exit("%s failed: %s" % (name, done.get("error")))
        toon_results[name] = {"result": done["result"], "share": outline_share(d, done, d.tmp)}
        print("  %-26s objects outlined %5.1f %%" % (name, 100.0 * toon_results[name]["share"][0]), flush=True)
    bench.end([r for rs in results.values() for r in rs] + [t["result"] for t in toon_results.values()])
    print()
    if "bloom" in PARTS:
        bloom_table()
    if "ssao" in PARTS:
        ssao_table()
    if "chain" in PARTS:
        chain_table()
    if "toon" in PARTS:
        toon_table()
    benchrun.write_json(args.json, {"repeats": results, "toon": toon_results}, indent=1)
finally:
    d.stop()
    d.cleanup()
