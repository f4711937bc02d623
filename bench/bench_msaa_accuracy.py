#!/usr/bin/env python3
"""MSAA against the true image (issue 22): every technique at msaa 1 and at
the device's highest level (4 on llvmpipe), scored against forward
supersampled N times in width and height (`"reference": {"technique":
"forward", "supersample": N}`, box-filtered in linear light), so that
anti-aliasing's gain shows where an aliased forward reference hides it.
Accuracy is a pure function of the frame, so nothing is interleaved or
repeated: one job each. Prints, per technique, the worst capture's mean SSIM
and FLIP mean at each level, and the change.

  bench/bench_msaa_accuracy.py [--techniques a,b,...] [--supersample 4]
      [--preset lights] [--lights 64] [--width 240 --height 160] [--json FILE]

At msaa > 1 the reference renders at the job's msaa too (the harness's
rule), so both levels are scored against a truth of N x N or more samples a
pixel."""


import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--techniques", default="", help="default: every registered technique")
ap.add_argument("--supersample", type=int, default=4)
ap.add_argument("--preset", default="lights")
ap.add_argument("--lights", type=int, default=64)
ap.add_argument("--width", type=int, default=240)
ap.add_argument("--height", type=int, default=160)
ap.add_argument("--json", help="write every result here")
args = ap.parse_args()

bench = benchrun.Run()
bench.start()
d = testlib.Daemon()
results = {}
try:
    info = d.json("GET", "/v1/info")[1]
    techs = [t for t in args.techniques.split(",") if t] or \
        [t["name"] for t in info.get("techniques", [])]
    top = info.get("device", {}).get("caps", {}).get("max_msaa", 1)
    levels = [1, top] if top > 1 else [1]
    print("scene: %s preset, %d lights, %dx%d; reference forward supersampled %d; msaa %s"
          % (args.preset, args.lights, args.width, args.height, args.supersample,
             " and ".join(map(str, levels))))
    for tech in techs:
        for level in levels:
            job = {"technique": tech, "msaa": level, "frames": 2, "warmup_frames": 1,
                   "capture_interval": 2, "metrics": ["ssim", "flip"],
                   "reference": {"technique": "forward", "supersample": args.supersample},
                   "osl": {"resolution": "auto"},
                   "scene": {"preset": args.preset, "lights": args.lights,
                             "width": args.width, "height": args.height}}
            if tech != "osl":
                del job["osl"]
            done = d.run(job)
            q = done.get("result", {}).get("quality", {})
            results[(tech, level)] = {
                "status": done.get("status"), "error": done.get("error"),
                "ssim": q.get("worst_ssim", {}).get("value"),
                "flip": q.get("worst_flip", {}).get("mean")}
            print("  %-20s msaa %d: %s" % (tech, level, results[(tech, level)]))
finally:
    testlib.stop_and_check(d)

print("\n| technique | SSIM, msaa 1 | SSIM, msaa %d | FLIP mean, msaa 1 | FLIP mean, msaa %d | better at msaa %d |"
      % (levels[-1], levels[-1], levels[-1]))
print("|---|---|---|---|---|---|")
for tech in techs:
    a, b = results.get((tech, 1), {}), results.get((tech, levels[-1]), {})
    if a.get("ssim") is None or b.get("ssim") is None:
        print("| %s | %s | %s | | | failed |" % (tech, a.get("error"), b.get("error")))
        continue
    better = b["ssim"] > a["ssim"] and b["flip"] < a["flip"]
    print("| %s | %.5f | %.5f | %.5f | %.5f | %s |"
          % (tech, a["ssim"], b["ssim"], a["flip"], b["flip"], "yes" if better else "**no**"))
benchrun.write_json(args.json, {"%s/%d" % k: v for k, v in results.items()}, indent=1)
bench.end([])
