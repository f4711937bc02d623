"""The many-lights family against forward, beyond the conformance bar of
e2e_techniques.py:
- accuracy: every technique at defaults matches forward at SSIM >= 0.999 and
  passes PerceptualDiff, on the thesis grid (10 and 256 lights) and the
  lights preset (16, 256 and 1,024 lights), and with an orbiting camera;
  every lossless non-default option does too;
- lossy layouts show their loss: xy_reconstruct_z scores a higher FLIP
  than the default layout (and no better SSIM); the colour packings stay
  within 1 (pack_shift) and 2 (pack_base10) levels of the default layout,
  saturated white included, and each differs somewhere;
- overflow is never silent: a tiny max_lights_per_cluster with many lights
  is counted per frame; under "fallback" the image still matches, under
  "fail" the job fails naming the option and the overflow; a sweep's
  no_overflow criterion bisects the light count to the bound;
- the heat map: served as a PNG per capture, with a mean and max that grow
  with the light count;
- frame k is a pure function of k (the same capture after 1 or 3 warm-up
  frames);
- bad options answer 400 naming the field; a grid only the device refuses
  fails the job at create, naming the field.
Small frames (160x120), few frames, so the suite stays short on 2 cores.
Forward's reference is most of the cost (1,024 lights: 1.7 CPU seconds a
frame at 160x120 on llvmpipe), and every technique of a scene is scored
against the same image (frame k is a pure function of k): the first job of
a scene renders it in the daemon and is scored there, the others are scored
against that served reference by shadebench-compare, the daemon's metrics
code, whose figures on the same PNGs are the daemon's to the last digit."""

import json
import os
import subprocess
import xml.etree.ElementTree as ET

import testlib
from testlib import check

testlib.skip_without_egl()

SSIM_BOUND = 0.999
COMPARE = os.environ.get("SHADEBENCH_COMPARE", "./shadebench-compare")
# The frame the accuracy jobs capture: the second timed one, after the
# harness's own frames, the warm-up and a timed frame have moved the lights
# (and the orbiting camera) and rebuilt the lists.
FRAMES = 2


def layout_of(path):
    """The layout a chart's SVG carries in its metadata."""
    meta = [e for e in ET.parse(path).getroot().iter()
            if e.tag.endswith("metadata") and e.get("id") == "shadebench-chart"]
    return json.loads(meta[0].text) if meta else None


TECHS = ["deferred", "tiled_deferred", "forward_plus", "clustered_forward", "clustered_deferred"]


def job(tech, lights=64, opts=None, frames=FRAMES, capture=FRAMES, preset="grid", camera="static",
        **extra):
    j = {"technique": tech, "frames": frames, "warmup_frames": 1, "capture_interval": capture,
         "reference": "forward", "metrics": ["ssim", "pdiff", "flip"],
         "scene": {"preset": preset, "width": 160, "height": 120, "dynamic": True,
                   "lights": lights, "camera": camera}}
    if opts is not None:
        j[tech] = opts
    j.update(extra)
    if j.get("reference") is None:
        del j["reference"], j["metrics"]
    return j


def quality(done):
    """(worst SSIM, worst FLIP mean, PerceptualDiff passed on every capture)."""
    caps = done.get("result", {}).get("captures", [])
    ms = [c.get("metrics", {}) for c in caps]
    if not ms:
        return 0.0, 1.0, False
    return (min(m.get("ssim", 0) for m in ms), max(m.get("flip", {}).get("mean", 1) for m in ms),
            all(m.get("pdiff", {}).get("pass") for m in ms))


# Forward's reference frames by scene and captured frames: {frame: path}.
references = {}


def scored(d, j):
    """Runs j, its captures scored against forward (j's reference). The
    first job of a scene and frames runs as it is (the daemon renders the
    reference and scores it) and keeps the served reference frames; a later
    one runs without a reference and its captures get the figures
    shadebench-compare gives against those frames, as result.captures[i].
    metrics. Returns (job, where the figures came from)."""
    key = json.dumps([j["scene"], j["frames"], j["capture_interval"]], sort_keys=True)
    shared = references.get(key)
    if j.get("reference") != "forward":
        return d.run(j), "daemon"
    if shared is None:
        done = d.run(j)
        caps = done.get("result", {}).get("captures", [])
        refs = {}
        for c in caps:
            path = os.path.join(d.tmp, "ref-%d-%d.png" % (len(references), c["frame"]))
            if d.download("/v1/jobs/%s/reference/%d.png" % (done["id"], c["frame"]), path) == 200:
                refs[c["frame"]] = path
        if caps and len(refs) == len(caps):
            references[key] = refs
        return done, "daemon"
    own = {k: v for k, v in j.items() if k not in ("reference", "metrics")}
    done = d.run(own)
    for c in done.get("result", {}).get("captures", []):
        path = os.path.join(d.tmp, "capture.png")
        c["metrics"] = {}
        if c.get("frame") in shared and d.download(c["url"], path) == 200:
            out = subprocess.run([COMPARE, shared[c["frame"]], path, "--metrics", ",".join(j["metrics"])],
                                 capture_output=True, text=True)
            if out.returncode in (0, 1):
                c["metrics"] = json.loads(out.stdout)
    return done, "compare"


def matches(d, j, what):
    done, where = scored(d, j)
    ok = check(done.get("status") == "done", "%s runs: %s" % (what, done.get("error")))
    ssim, flip, pdiff = quality(done)
    print("  %-60s SSIM %.6f  FLIP %.5f  PerceptualDiff %s (%s)" % (what, ssim, flip, pdiff, where))
    if ok:
        check(ssim >= SSIM_BOUND and pdiff,
              "%s matches forward: SSIM %.6f >= %s, PerceptualDiff %s" % (what, ssim, SSIM_BOUND, pdiff))
    return done, ssim, flip


d = testlib.Daemon()
try:
    # Accuracy at defaults: the thesis grid, and the lights preset with 16,
    # 256 and 1,024 lights; then a moving camera (the grid's slices and the
    # CPU binning follow it).
    for preset, counts in (("grid", (10, 256)), ("lights", (16, 256, 1024))):
        for lights in counts:
            for tech in TECHS:
                matches(d, job(tech, lights, preset=preset),
                        "%s at defaults, %s, %d lights" % (tech, preset, lights))
    for tech, opts in (("clustered_deferred", {}), ("tiled_deferred", {"binning": "cpu"})):
        matches(d, job(tech, 256, opts, preset="lights", camera="orbit"),
                "%s %s, lights, 256 lights, orbiting camera" % (tech, opts))

    # The forward family draws forward's image bit for bit, where surfaces
    # meet too: at 480x320 a cube's edge on the ground is a depth tie at
    # (126,243), which the pre-pass's GL_LEQUAL gave to the surface drawn last
    # (PSNR 80.8) until a stencil mark kept the first, as forward's GL_LESS does.
    for tech in ("forward_plus", "clustered_forward"):
        tie = job(tech, 256, preset="lights", metrics=["psnr"], frames=1, capture=1)
        tie["scene"] = {"preset": "lights", "lights": 256, "width": 480, "height": 320}
        done, where = scored(d, tie)
        psnr = (done.get("result", {}).get("captures") or [{}])[0].get("metrics", {}).get("psnr", {})
        print("  %-60s %s (%s)" % ("%s against forward, 480x320, 256 lights" % tech, psnr, where))
        check(done.get("status") == "done" and psnr.get("identical") is True,
              "%s is bit-identical to forward where a cube meets the ground: %s %s"
              % (tech, done.get("error"), psnr))

    # Every lossless non-default option, on the grid with 64 lights.
    lossless = [
        ("deferred", {"light_bounds": "scissor_loose"}),
        ("deferred", {"light_bounds": "volume"}),
        ("deferred", {"light_bounds": "fullscreen"}),
        ("deferred", {"gbuffer": {"normal": "float3"}}),
        ("tiled_deferred", {"binning": "cpu"}),
        ("tiled_deferred", {"tile_size": 8}),
        ("tiled_deferred", {"tile_size": 128, "binning": "cpu"}),
        ("forward_plus", {"tile_size": 128}),
        ("clustered_forward", {"grid": [32, 18, 48], "slices": "linear"}),
        ("clustered_deferred", {"grid": [4, 3, 2], "slices": "linear", "max_lights_per_cluster": 64}),
        ("clustered_deferred", {"overflow": "fail", "gbuffer": {"normal": "float3"}}),
    ]
    for tech, opts in lossless:
        matches(d, job(tech, 64, opts), "%s %s" % (tech, opts))

    # Lossy layouts show their loss against the default layout.
    for tech in ("deferred", "clustered_deferred"):
        _, base_ssim, base_flip = matches(d, job(tech, 64), "%s default layout" % tech)
        done, where = scored(d, job(tech, 64, {"gbuffer": {"normal": "xy_reconstruct_z"}}))
        ssim, flip, pdiff = quality(done)
        print("  %-60s SSIM %.6f  FLIP %.5f  PerceptualDiff %s (%s)"
              % ("%s xy_reconstruct_z" % tech, ssim, flip, pdiff, where))
        check(done.get("status") == "done" and flip > base_flip and ssim <= base_ssim + 1e-5,
              "%s gbuffer xy_reconstruct_z shows its loss: FLIP %.5f > %.5f, SSIM %.6f vs %.6f"
              % (tech, flip, base_flip, ssim, base_ssim))

    # The colour packings' loss is a few levels, never a wrong hue: against
    # the default layout's frame, on the grid and on the sphere preset's
    # white (saturated: every channel 1.0, where the seed's layouts turned
    # white black and red), pack_shift is at most 1 level off (a byte of 255
    # is kept to 254) and pack_base10 at most 2 (100 levels a channel), and
    # each differs somewhere (its loss stays visible).
    bound = {"pack_shift": 1, "pack_base10": 2}
    for tech in ("deferred", "clustered_deferred"):
        for preset in ("grid", "sphere"):
            plain = d.run(job(tech, 16, preset=preset, reference=None))
            base = os.path.join(d.state, "jobs", plain["id"], "frame-%06d.png" % FRAMES)
            for layout in ("pack_shift", "pack_base10"):
                packed = d.run(job(tech, 16, {"gbuffer": {"albedo": layout}}, preset=preset,
                                   reference=None))
                diff = testlib.png_diff(base, os.path.join(d.state, "jobs", packed["id"],
                                                           "frame-%06d.png" % FRAMES))
                differs = (diff or {}).get("differing_pixels", 0)
                print("  %-60s %s" % ("%s %s %s" % (tech, layout, preset), diff))
                check(packed.get("status") == "done" and diff is not None and
                      diff["max_abs"] <= bound[layout],
                      "%s %s on %s stays within %d level(s) of rgba8: %s"
                      % (tech, layout, preset, bound[layout], diff))
                if (layout, preset) in (("pack_shift", "sphere"), ("pack_base10", "grid")):
                    check(differs > 0, "%s %s on %s shows its loss: %d pixels differ"
                          % (tech, layout, preset, differs))

    # Overflow, forced: 256 lights, at most 4 a cluster.
    tiny = {"max_lights_per_cluster": 4}
    done, _, _ = matches(d, job("clustered_deferred", 256, dict(tiny, overflow="fallback")),
                         "clustered_deferred overflowing with fallback")
    ov = done.get("result", {}).get("clustered_deferred", {}).get("overflow", {})
    check(ov.get("frames") == FRAMES and ov.get("cells_per_frame", {}).get("max", 0) > 0
          and ov.get("entries_unlisted_per_frame", {}).get("max", 0) > 0
          and ov.get("first_frame") == 1,
          "fallback counts the overflow per frame: %s" % ov)
    check(ov.get("lights_dropped_per_frame", {}).get("max", -1) == 0,
          "fallback drops no light, and the counter says so: %s"
          % ov.get("lights_dropped_per_frame"))
    for tech in ("clustered_forward", "clustered_deferred"):
        done = d.run(job(tech, 256, dict(tiny, overflow="fail")))
        err = done.get("error") or ""
        check(done.get("status") == "failed" and "overflow" in err
              and "%s.max_lights_per_cluster" % tech in err,
              "%s overflow fail fails the job naming it: %s %s" % (tech, done.get("status"), err))
    # A sweep finds the light count from which a cluster bound overflows:
    # the breaking point's fullest cluster fits the bound, the first failing
    # count's does not, and every row counts its overflowing frames. The
    # bound (8) is passed at 64 lights: from 1 to 128 the search takes 9
    # probes (to 1,024, 12, whose overflowing 1,024, 512 and 256 lights,
    # shaded through the fallback, took 12 of the sweep's 15 CPU seconds).
    tight = 8
    status, sub = d.json("POST", "/v1/sweeps", {
        "base": {"technique": "clustered_deferred", "frames": 2, "warmup_frames": 0, "capture_interval": 2,
                 "scene": {"preset": "lights", "width": 160, "height": 120},
                 "clustered_deferred": {"max_lights_per_cluster": tight}},
        "find": {"param": "scene.lights", "from": 1, "to": 128, "while": "no_overflow", "steps": 12}})
    sw = d.wait_sweep(sub["id"]) if status == 202 else {}
    bp = sw.get("result", {}).get("breaking_point", {})
    rows = {r["values"]["scene.lights"]: r for r in sw.get("points", [])}
    check(sw.get("status") == "done" and bp.get("outcome") == "boundary" and bp.get("criterion") == "no_overflow"
          and bp.get("first_failing") == bp.get("value", -2) + 1, "no_overflow bisects to a boundary: %s" % bp)

    def fullest(n):
        r = d.json("GET", "/v1/jobs/" + rows[n]["job"])[1].get("result", {})
        return r.get("clustered_deferred", {}).get("lights_per_cell", {}).get("fullest", {}).get("max", -1)
    if bp.get("outcome") == "boundary":
        ok, bad = rows[bp["value"]], rows[bp["first_failing"]]
        check(ok.get("light_overflow_frames") == 0 and bad.get("light_overflow_frames") == 2 and
              ok.get("criterion_holds") is True and bad.get("criterion_holds") is False,
              "rows count the overflowing frames: %s / %s" % (ok.get("light_overflow_frames"),
                                                              bad.get("light_overflow_frames")))
        check(0 < fullest(bp["value"]) <= tight < fullest(bp["first_failing"]),
              "the breaking point is where the fullest cluster passes the bound: %s, %s"
              % (fullest(bp["value"]), fullest(bp["first_failing"])))

    # Nothing bounded to overflow: the sweep fails on its first probe,
    # naming the criterion, instead of finding that it holds everywhere.
    status, sub = d.json("POST", "/v1/sweeps", {
        "base": {"technique": "forward", "frames": 2, "warmup_frames": 0, "capture_interval": 2,
                 "scene": {"preset": "lights", "width": 160, "height": 120}},
        "find": {"param": "scene.lights", "from": 1, "to": 64, "while": "no_overflow"}})
    sw = d.wait_sweep(sub["id"]) if status == 202 else {}
    check(sw.get("status") == "failed" and sw.get("error", "").startswith("find.while:") and
          "look.shadows" in sw.get("error", "") and len(sw.get("points", [])) == 1,
          "no_overflow on forward fails naming the criterion: %s %s" % (sw.get("status"), sw.get("error")))

    # A sweep over technique and light count charts time against the light
    # count, a line per technique, and its report names the crossovers.
    status, sub = d.json("POST", "/v1/sweeps", {
        "base": {"frames": 2, "warmup_frames": 0, "capture_interval": 2,
                 "scene": {"preset": "lights", "width": 160, "height": 120}},
        "vary": {"technique": ["forward", "clustered_deferred"], "scene.lights": [4, 64]}})
    sw = d.wait_sweep(sub["id"]) if status == 202 else {}
    check(sw.get("status") == "done" and len(sw.get("points", [])) == 4 and
          list(sw["points"][0]["values"]) == ["technique", "scene.lights"],
          "a grid over technique and light count, values in vary's order")
    path = os.path.join(d.tmp, "tvp.svg")
    tvp = (layout_of(path) if d.download("/v1/sweeps/%s/charts/time_vs_param.svg" % sub.get("id"), path) == 200
           else None) or {}
    pts = tvp.get("points", [])
    check(sorted({p["x"] for p in pts}) == [4, 64] and
          {p["series"] for p in pts} == {"forward (reference)", "clustered_deferred"} and
          "scene.lights" in tvp.get("xlabel", "") and tvp.get("x_log") is True,
          "time_vs_param: x is the light count (log), a line per technique: %s %s"
          % (tvp.get("xlabel"), sorted({p.get("series") for p in pts})))
    page = d.request("GET", "/v1/sweeps/%s/report.html" % sub.get("id"))[2].decode()
    check("<h2>Verdict</h2>" in page and "scene.lights" in page, "the report's verdict reads along the light count")

    # No overflow at defaults: the counters read zero.
    done = d.run(job("clustered_forward", 64, capture=0, reference=None))
    ov = done.get("result", {}).get("clustered_forward", {}).get("overflow", {})
    check(ov.get("frames") == 0 and ov.get("first_frame") is None, "no overflow at defaults: %s" % ov)

    # The heat map grows with the light count and is served beside the frames,
    # on one absolute scale (the same colour is the same count in every job:
    # 16 lights never reach white, which per-image scaling gave the largest
    # count of any map), with the scale in the result and a legend strip
    # under the map.
    means, legends = [], []
    for lights in (16, 256):
        done = d.run(job("clustered_deferred", lights, frames=2, capture=1, reference=None))
        heat = done.get("result", {}).get("heatmap", {})
        caps = heat.get("captures", [])
        scale = heat.get("scale") or {}
        check(len(caps) == 2 and heat.get("unit") and heat.get("ramp") and
              scale.get("max") == 65536 and scale.get("map_rows") == 120 and
              scale.get("ticks", [None])[-1] == 65536,
              "heat map per capture, on the one scale: %s" % heat)
        if caps:
            means.append(caps[-1]["mean"])
            path = os.path.join(d.tmp, "heat%d.png" % lights)
            info = testlib.png_info(path) if d.download(caps[-1]["url"], path) == 200 else None
            check(info and info.get("width") == 160 and
                  info.get("height") == 120 + scale.get("legend_rows", -1),
                  "heat map PNG served at %s, the legend under the map: %s" % (caps[-1]["url"], info))
            check(caps[-1]["max"] >= caps[-1]["mean"] > 0, "heat map figures: %s" % caps[-1])
            if info:
                w, h, px = testlib.png_pixels(path)
                legends.append(px[120 * w:])
                whites = sum(1 for p in px[:120 * w] if p == (255, 255, 255))
                check(lights != 16 or whites == 0,
                      "16 lights stay far from white on the absolute scale: %d white pixels" % whites)
            status, _, _ = d.request("GET", "/v1/jobs/%s/heatmap/99.png" % done["id"])
            check(status == 404, "no heat map for an uncaptured frame: %d" % status)
    check(len(means) == 2 and means[1] > 2 * means[0], "heat grows with the lights: %s" % means)
    check(len(legends) == 2 and legends[0] == legends[1] and legends[0],
          "the legend strip is the same in every map")
    done = d.run(job("forward", 16, frames=2, capture=1, reference=None))
    check("heatmap" not in done.get("result", {}), "forward publishes no heat map")

    # Frame k is a pure function of k: the same capture after 1 or 3 warm-up
    # frames (lists, rings and records carry nothing into the image).
    for tech, opts in (("clustered_deferred", {}), ("tiled_deferred", {"binning": "cpu"}),
                       ("deferred", {"light_bounds": "volume"})):
        paths = []
        for warmup in (1, 3):
            done = d.run(job(tech, 256, opts, frames=3, capture=3, preset="lights", reference=None,
                             warmup_frames=warmup))
            paths.append(os.path.join(d.tmp, "%s-w%d.png" % (tech, warmup)))
            check(done.get("status") == "done" and
                  d.download(done["result"]["captures"][-1]["url"], paths[-1]) == 200,
                  "%s renders: %s" % (tech, done.get("error")))
        diff = testlib.png_diff(*paths)
        check(diff and diff["max_abs"] == 0, "%s %s: frame 3 the same after 1 or 3 warm-up frames: %s"
              % (tech, opts, diff))

    # Bad options: 400 naming the field.
    base = {"frames": 2, "scene": {"width": 160, "height": 120}}
    testlib.rejects(d, dict(base, technique="tiled_deferred", tiled_deferred={"tile_size": 0}),
                    "tiled_deferred.tile_size")
    testlib.rejects(d, dict(base, technique="forward_plus", forward_plus={"tile_size": 256}),
                    "forward_plus.tile_size")
    testlib.rejects(d, dict(base, technique="deferred", deferred={"gbuffer": {"normal": "spherical"}}),
                    "deferred.gbuffer.normal")
    testlib.rejects(d, dict(base, technique="clustered_deferred",
                            clustered_deferred={"gbuffer": {"albedo": "rgb565"}}),
                    "clustered_deferred.gbuffer.albedo")
    testlib.rejects(d, dict(base, technique="clustered_forward", clustered_forward={"grid": [16, 9]}),
                    "clustered_forward.grid")
    testlib.rejects(d, dict(base, technique="clustered_forward",
                            clustered_forward={"grid": [1024, 1024, 2]}), "clustered_forward.grid")
    testlib.rejects(d, dict(base, technique="clustered_deferred",
                            clustered_deferred={"max_lights_per_cluster": 0}),
                    "clustered_deferred.max_lights_per_cluster")
    testlib.rejects(d, dict(base, technique="clustered_deferred", clustered_deferred={"overflow": "drop"}),
                    "clustered_deferred.overflow")
    # Grids only the device (or the image) refuses: the job fails at create,
    # naming the field and the limit. The bit buffer takes cells x lights / 8
    # bytes: pick a grid just past this device's storage-buffer limit.
    caps = d.json("GET", "/v1/info")[1].get("device", {}).get("caps", {})
    lights = 65536
    cells = caps.get("max_ssbo_bytes", 1 << 27) // (lights // 8) + 1
    z = -(-cells // (160 * 120))
    refusals = [([200, 9, 24], "image", 1024)]
    if 160 * 120 * z <= 1 << 20:
        refusals.append(([160, 120, z], "GL_MAX_SHADER_STORAGE_BLOCK_SIZE", lights))
    for grid, why, n in refusals:
        done = d.run(dict(base, technique="clustered_deferred",
                          scene={"preset": "lights", "width": 160, "height": 120, "lights": n},
                          clustered_deferred={"grid": grid}))
        err = done.get("error") or ""
        check(done.get("status") == "failed" and "clustered_deferred.grid" in err and why in err,
              "grid %s refused at create: %s" % (grid, err))
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_many_lights")
