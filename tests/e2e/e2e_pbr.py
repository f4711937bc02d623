"""Physically based shading, image-based lighting and shadows (issue 12):
- white furnace: a white, rough, dielectric sphere on a white ground under a
  uniform environment renders at the environment's radiance everywhere, in
  forward and in a deferred technique;
- energy never grows with roughness: a white metal in the same furnace
  reflects less as it gets rougher, and never more than the environment;
- roughness 0 (clamped, and counted) lets no NaN or infinity into a capture,
  in 32- and 16-bit HDR targets;
- shadows: a light straight above a sphere darkens the ground under it, and
  nothing else (no pixel darker where no shadow can fall, no acne on lit
  surfaces);
- the shadow atlas overflows, forced: the lights that lost their shadows
  are reported (drop_report) or the job fails naming them (fail);
- seed 002's scene (teapots, probes, shadows) with a culled deferred
  technique agrees with forward under the same look, with every pass timed
  in frame order and the setup time and atlas use in the result;
- bad options answer 400 naming the field.
Small frames and few of them: the whole file runs in about a minute on two
cores."""

import os

import testlib
from testlib import check

testlib.skip_without_egl()

W, H = 160, 120
ONE = {"frames": 1, "warmup_frames": 0, "capture_interval": 1}


def sphere(**scene):
    return dict({"preset": "sphere", "width": W, "height": H}, **scene)


def hdr(done):
    caps = done.get("result", {}).get("captures", [])
    return caps[-1].get("hdr", {}) if caps else {}


d = testlib.Daemon()
try:
    # Bad options: 400 naming the field.
    base = dict(ONE, scene=sphere())
    for look, field in (
            ({"lighting": "pbr", "ibl": {"probes": 33}}, "look.ibl.probes"),
            ({"lighting": "pbr", "ibl": {"probes": [{"position": [0, 1, 0]}]}},
             "look.ibl.probes[0].radius"),
            ({"lighting": "pbr", "ibl": {"resolution": 48}}, "look.ibl.resolution"),
            ({"lighting": "pbr", "ibl": {"environment": "studio"}}, "look.ibl.environment"),
            ({"lighting": "phong", "ibl": True}, "look.ibl"),
            ({"shadows": {"atlas": 3000}}, "look.shadows.atlas"),
            ({"shadows": {"overflow": "ignore"}}, "look.shadows.overflow"),
            ({"shadows": {"tile": 24}}, "look.shadows.tile"),
            ({"shadows": {"bias": -1}}, "look.shadows.bias"),
            ({"shadows": "yes"}, "look.shadows")):
        testlib.rejects(d, dict(base, look=look), field)
    testlib.rejects(d, dict(ONE, scene={"preset": "teapots", "teapot_segments": 0}),
                    "scene.teapot_segments")

    # White furnace: everything in view at the environment's 0.5.
    furnace = {"lighting": "pbr", "ibl": {"environment": "uniform", "intensity": 0.5}}
    for tech in ("forward", "clustered_deferred"):
        done = d.run(dict(ONE, technique=tech, look=furnace,
                          scene=sphere(lights=0, roughness=1.0, metallic=0.0)))
        h = hdr(done)
        check(done.get("status") == "done" and abs(h.get("min", 0) - 0.5) < 0.005 and
              abs(h.get("max", 1) - 0.5) < 0.005 and h.get("nonfinite") == 0,
              "%s: white furnace renders at the environment's radiance: %s (%s)"
              % (tech, h, done.get("error")))

    # Energy against roughness: a white metal reflects less as it roughens.
    means = []
    for r in (0.0, 0.25, 0.5, 0.75, 1.0):
        done = d.run(dict(ONE, look=furnace, scene=sphere(lights=0, roughness=r, metallic=1.0)))
        means.append(hdr(done).get("mean", [9])[0])
    check(all(b <= a + 1e-4 for a, b in zip(means, means[1:])) and max(means) <= 0.5 + 1e-4,
          "energy never grows with roughness and never exceeds the environment: %s" % means)

    # Roughness 0: clamped, counted, and no NaN reaches a capture.
    for fmt in ("rgba32f", "rgba16f"):
        done = d.run(dict(ONE, look={"lighting": "pbr", "hdr": fmt},
                          scene=sphere(roughness=0.0, metallic=1.0)))
        h = hdr(done)
        check(done.get("result", {}).get("pbr", {}).get("materials_clamped") == 2 and
              h.get("nonfinite") == 0 and h.get("max", 0) > 1.0,
              "%s: roughness 0 is clamped (2 materials) and stays finite: %s %s"
              % (fmt, done.get("result", {}).get("pbr"), h))

    # Shadows: the light straight above the sphere darkens the ground under
    # it and nothing else.
    pixels = {}
    for on in (False, True):
        look = {"lighting": "pbr", "shadows": {"pcf": 1} if on else False}
        done = d.run(dict(ONE, look=look, scene=sphere(roughness=0.6)))
        check(done.get("status") == "done", "shadow job runs: %s" % done.get("error"))
        path = os.path.join(d.tmp, "shadow-%d.png" % on)
        d.download(done["result"]["captures"][-1]["url"], path)
        pixels[on] = testlib.png_pixels(path)
        if on:
            sections = list(done["result"].get("gpu_sections_ms", {}))
            check(sections == ["shadows", "shading", "sky", "resolve"],
                  "the shadow pass runs first, the sky after the technique: %s" % sections)
            camera = done["result"]["scene"]["camera"]
            light = [0.0, 3.0, 0.0]
    (w, h, off), (_, _, on) = pixels[False], pixels[True]
    core, core_dark, outside_changed, lit_changed = testlib.sphere_shadow_counts(
        camera, off, on, w, h, testlib.towards_point(light))
    check(core > 100 and core_dark == core,
          "the ground under the sphere is in shadow: %d of %d pixels darker" % (core_dark, core))
    check(outside_changed == 0,
          "no pixel changes where no shadow can fall: %d changed" % outside_changed)
    check(lit_changed == 0, "no acne on the lit side of the sphere: %d changed" % lit_changed)

    # Overflow, forced: a 256 atlas holds 10 lights' faces at 32 texels.
    teapots = {"preset": "teapots", "lights": 16, "teapot_segments": 2, "width": W, "height": H}
    small = {"atlas": 256, "min_tile": 32, "max_tile": 64}
    done = d.run(dict(ONE, look={"lighting": "pbr", "shadows": small}, scene=teapots))
    sh = done.get("result", {}).get("shadows", {})
    over = sh.get("overflow", {})
    check(done.get("status") == "done" and over.get("frames_with_drops") == 1 and
          over.get("lights_dropped", 0) > 0 and len(over.get("lights", [])) == over["lights_dropped"]
          and sh.get("lights_mapped", {}).get("max") == 10,
          "overflow drops the least important lights and reports them: %s" % sh)
    done = d.run(dict(ONE, look={"lighting": "pbr", "shadows": dict(small, overflow="fail")},
                      scene=teapots))
    err = done.get("error") or ""
    check(done.get("status") == "failed" and "look.shadows.atlas" in err and
          "lights without shadows" in err, "overflow fail names the lights: %s" % err)

    # Seed 002's scene, small: probes, shadows, a culled deferred technique
    # against forward under the same look.
    look = {"lighting": "pbr", "ibl": {"probes": 3, "resolution": 32},
            "shadows": {"atlas": 1024, "max_tile": 64}}
    done = d.run({"technique": "clustered_deferred", "frames": 2, "warmup_frames": 0,
                  "capture_interval": 2, "reference": "forward", "look": look,
                  "scene": dict(teapots, lights=8)})
    r = done.get("result", {})
    q = r.get("quality", {})
    check(done.get("status") == "done" and q.get("worst_ssim", {}).get("value", 0) >= 0.999 and
          q.get("pdiff_failed_captures") == 0,
          "clustered deferred with probes and shadows agrees with forward: %s (%s)"
          % (q.get("worst_ssim"), done.get("error")))
    sections = list(r.get("gpu_sections_ms", {}))
    check(sections[0] == "shadows" and sections[-2:] == ["sky", "resolve"],
          "passes in frame order: %s" % sections)
    ibl = r.get("ibl", {})
    check(len(ibl.get("probes", [])) == 3 and len(ibl.get("blended_at_frame_1", [])) == 3 and
          ibl.get("setup_ms", {}).get("total", 0) > 0 and r.get("setup_ms", {}).get("look", 0) > 0,
          "probes, their blend and the setup time are reported: %s" % ibl.get("setup_ms"))
    check(r.get("shadows", {}).get("atlas_use", {}).get("fraction_max", 0) > 0 and
          r.get("scene", {}).get("teapot_tessellation", {}).get("segments") == 2,
          "atlas use and the teapots' tessellation are reported")
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_pbr")
