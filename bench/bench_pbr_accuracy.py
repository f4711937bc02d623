#!/usr/bin/env python3
"""The error of each part of seed 002's renderer (issue 12), in one run:

1. every technique with PBR, probes and shadows against forward with the
   same look, on `teapots` at 80 lights (SSIM, PerceptualDiff, FLIP);
2. seed 002's claim that deferred with SSAO and forward without it "look
   almost no different": clustered deferred with look.post ssao against
   forward with the same look but no post chain;
3. shadow quality against atlas size: the atlas (tiles by importance)
   against a large per-light map (one 512 cube map per light) on teapots;
4. shadow bias and normal offset: acne (lit pixels darkened where no
   shadow can fall) and peter-panning (pixels of the true umbra left lit)
   on the `sphere` preset, by ray casting the scene in Python;
5. probe count against the reflections: probes 0, 1, 3, 8 against 16.

  bench/bench_pbr_accuracy.py [--width W --height H] [--json FILE]"""

import json
import math
import os
import subprocess
import sys

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--width", type=int, default=320)
ap.add_argument("--height", type=int, default=240)
ap.add_argument("--json")
args = ap.parse_args()
COMPARE = os.environ.get("SHADEBENCH_COMPARE", "build/shadebench-compare")
W, H = args.width, args.height
ONE = {"frames": 1, "warmup_frames": 0, "capture_interval": 1}
teapots = {"preset": "teapots", "width": W, "height": H, "teapot_segments": 8}
out = {}


def run(d, job):
    done = d.wait(d.submit(job), timeout=7200)
    if done.get("status") != "done":
        sys.exit("job failed: %s\n%s" % (done.get("error"), json.dumps(job)))
    return done


def capture(d, job, name):
    done = run(d, job)
    path = os.path.join(d.tmp, name + ".png")
    d.download(done["result"]["captures"][-1]["url"], path)
    return path, done


def compare(a, b):
    r = subprocess.run([COMPARE, a, b, "--metrics", "ssim,pdiff,flip"], capture_output=True, text=True)
    m = json.loads(r.stdout)
    return m["ssim"], m["pdiff"]["failing_pixels"], m["flip"]["mean"]


def quality(done):
    q = done["result"]["quality"]
    return (q["worst_ssim"]["value"], q["pdiff_failed_captures"], q["worst_flip"]["mean"])


d = testlib.Daemon()
try:
    info = d.json("GET", "/v1/info")[1]
    print("device: %s\n" % info["device"]["gl_renderer"])
    names = [t["name"] for t in info["techniques"] if t["name"] not in ("forward", "unlit")]

    print("1. Every technique against forward, PBR + 3 probes + shadows, teapots, 80 lights\n")
    print("| technique | SSIM | PerceptualDiff failing captures | FLIP mean |")
    print("|---|---|---|---|")
    look = {"lighting": "pbr", "ibl": {"probes": 3}, "shadows": {"atlas": 4096}}
    out["techniques"] = {}
    for t in names:
        done = run(d, dict(ONE, technique=t, reference="forward", look=look,
                           scene=dict(teapots, lights=80)))
        s, p, f = quality(done)
        out["techniques"][t] = [s, p, f]
        print("| %s | %.5f | %d | %.5f |" % (t, s, p, f), flush=True)

    print("\n2. Deferred with SSAO against forward without it (seed 002's comparison)\n")
    print("| technique | SSIM | PerceptualDiff failing pixels | FLIP mean |")
    print("|---|---|---|---|")
    job = dict(ONE, technique="clustered_deferred", reference="forward",
               look={"lighting": "pbr", "ibl": {"probes": 3}, "post": ["ssao"]},
               reference_look={"lighting": "pbr", "ibl": {"probes": 3}},
               scene=dict(teapots, lights=80))
    done = run(d, job)
    m = done["result"]["captures"][-1]["metrics"]
    out["ssao"] = m
    print("| clustered_deferred + ssao | %.5f | %d (%s) | %.5f |"
          % (m["ssim"], m["pdiff"]["failing_pixels"], "pass" if m["pdiff"]["pass"] else "fail",
             m["flip"]["mean"]), flush=True)

    print("\n3. Shadow quality against atlas size (forward, teapots, 16 lights), against "
          "one 512 cube map per light\n")
    print("| atlas | lights mapped | faces by size | texels used | SSIM | PerceptualDiff failing pixels | FLIP mean |")
    print("|---|---|---|---|---|---|---|")
    ref, _ = capture(d, dict(ONE, look={"lighting": "pbr", "shadows": {"layout": "cubes", "tile": 512,
                                                                        "atlas": 8192}},
                             scene=dict(teapots, lights=16)), "cubes512")
    out["atlas"] = {}
    for atlas in (256, 512, 1024, 2048, 4096):
        path, done = capture(d, dict(ONE, look={"lighting": "pbr",
                                                "shadows": {"atlas": atlas, "min_tile": 16}},
                                     scene=dict(teapots, lights=16)), "atlas%d" % atlas)
        sh = done["result"]["shadows"]
        s, p, f = compare(ref, path)
        out["atlas"][atlas] = [s, p, f, sh]
        print("| %d | %.0f | %s | %.0f | %.5f | %d | %.5f |"
              % (atlas, sh["lights_mapped"]["mean"], json.dumps(sh["faces_by_size_at_frame_1"]),
                 sh["atlas_use"]["texels_mean"], s, p, f), flush=True)

    print("\n4. Bias and normal offset on the sphere (light straight above), "
          "acne and peter-panning counted by ray casting\n")
    print("| bias | normal_offset | acne pixels | umbra pixels left lit | umbra pixels |")
    print("|---|---|---|---|---|")
    base = dict(ONE, scene={"preset": "sphere", "roughness": 0.6, "width": W, "height": H})
    off_path, done = capture(d, dict(base, look={"lighting": "pbr"}), "noshadow")
    cam = done["result"]["scene"]["camera"]
    off = testlib.png_pixels(off_path)
    out["bias"] = []
    for bias, offset in ((0.0, 0.0), (0.005, 0.0), (0.02, 0.0), (0.02, 1.0), (0.1, 1.0),
                         (0.3, 1.0), (0.0, 3.0)):
        path, _ = capture(d, dict(base, look={"lighting": "pbr", "shadows": {
            "bias": bias, "normal_offset": offset}}), "bias")
        on = testlib.png_pixels(path)
        eye, target = cam["eye_at_frame_0"], cam["target_at_frame_0"]
        fwd = [t - e for t, e in zip(target, eye)]
        n = math.sqrt(sum(c * c for c in fwd))
        fwd = [c / n for c in fwd]
        right = [-fwd[2], 0.0, fwd[0]]
        n = math.sqrt(sum(c * c for c in right))
        right = [c / n for c in right]
        up = [right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2],
              right[0] * fwd[1] - right[1] * fwd[0]]
        th = math.tan(math.radians(cam["fovy_deg"]) / 2)
        light = [0.0, 3.0, 0.0]
        acne = lit_umbra = umbra = 0
        w, h = off[0], off[1]
        for y in range(h):
            for x in range(w):
                sx = (2 * (x + 0.5) / w - 1) * th * w / h
                sy = (1 - 2 * (y + 0.5) / h) * th
                dv = [f + sx * r + sy * u for f, r, u in zip(fwd, right, up)]
                n = math.sqrt(sum(c * c for c in dv))
                dv = [c / n for c in dv]
                a = sum(off[2][y * w + x]) / 3.0
                b = sum(on[2][y * w + x]) / 3.0
                bb = sum(e * c for e, c in zip(eye, dv))
                disc = bb * bb - (sum(e * e for e in eye) - 0.64)
                if disc >= 0 and -bb - math.sqrt(disc) > 0:
                    t = -bb - math.sqrt(disc)
                    p = [e + t * c for e, c in zip(eye, dv)]
                    lv = [l - q for l, q in zip(light, p)]
                    nl = sum(q * c for q, c in zip(p, lv)) / (0.8 * math.sqrt(sum(c * c for c in lv)))
                    acne += nl > 0.05 and b < a - 2
                    continue
                if dv[1] >= 0:
                    continue
                t = (-0.8 - eye[1]) / dv[1]
                g = [e + t * c for e, c in zip(eye, dv)]
                if abs(g[0]) > 5.5 or abs(g[2]) > 5.5:
                    continue
                # Distance from the sphere's centre to the segment ground -> light.
                sd = [l - q for l, q in zip(light, g)]
                sl = math.sqrt(sum(c * c for c in sd))
                sd = [c / sl for c in sd]
                tt = min(max(-sum(q * c for q, c in zip(g, sd)), 0.0), sl)
                dist = math.sqrt(sum((q + tt * c) ** 2 for q, c in zip(g, sd)))
                if dist < 0.8 * 0.97:
                    umbra += 1
                    lit_umbra += b > 0.6 * a
                elif dist > 0.8 * 1.15 + 0.05 and b < a - 2:
                    acne += 1
        out["bias"].append([bias, offset, acne, lit_umbra, umbra])
        print("| %g | %g | %d | %d | %d |" % (bias, offset, acne, lit_umbra, umbra), flush=True)

    print("\n5. Probe count against the reflections (forward, teapots, 8 lights), against 16 probes\n")
    print("| probes | SSIM | PerceptualDiff failing pixels | FLIP mean | setup ms |")
    print("|---|---|---|---|---|")
    ref, _ = capture(d, dict(ONE, look={"lighting": "pbr", "ibl": {"probes": 16}},
                             scene=dict(teapots, lights=8)), "probes16")
    out["probes"] = {}
    for probes in (0, 1, 3, 8):
        path, done = capture(d, dict(ONE, look={"lighting": "pbr", "ibl": {"probes": probes}},
                                     scene=dict(teapots, lights=8)), "probes%d" % probes)
        s, p, f = compare(ref, path)
        setup = done["result"]["ibl"]["setup_ms"]["total"]
        out["probes"][probes] = [s, p, f, setup]
        print("| %d | %.5f | %d | %.5f | %.0f |" % (probes, s, p, f, setup), flush=True)
finally:
    d.stop()
    d.cleanup()

benchrun.write_json(args.json, out, indent=1)
