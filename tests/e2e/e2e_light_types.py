"""Spot and directional lights (issue 21), on the lights preset at 160x120:
- every technique (from /v1/info; unlit, the cost floor, excepted) shades
  generated spot lights and the sun as forward does: the many-lights family
  at e2e_many_lights' bar (SSIM >= 0.999 and PerceptualDiff), OSL at the
  conformance bar of e2e_techniques (0.995); forward_plus and
  clustered_forward bit for bit; deferred's every light bound and tiled
  deferred's CPU binning too; with moving lights and an orbiting camera;
- spots are binned by their cone: with the same lights as spots of the same
  radius, the grid's light evaluations per pixel (the heat map's mean) and
  the lights per cell are well under the points' (at most 60%);
- the directional light is in every cell: with the sun alone the culling
  techniques are forward's image (bit for bit where forward's family is),
  every surface pixel evaluates exactly one light, and the sun brightens
  (almost) every surface pixel against ambient alone (all but the faces
  turned away from it);
- spot cones visibly limit the lit area: fewer pixels differ from the
  ambient-only image under spots than under the same lights as points;
- MSAA 4 (clustered forward bit for bit, clustered deferred's per-sample
  lighting) and PBR agree too;
- shadows: spots cast with the omni maps (deferred with shadows agrees with
  forward with shadows; a spot pointing down draws one face), the sun
  with its own orthographic map: ray-cast on the sphere preset for the sun
  and for a spot, the ground the sphere hides from the light is darker,
  nothing else changes, no acne on its lit side;
- the scene options: written back in the spec, described by type, bad
  values answered 400 naming the field; a sweep varies scene.light_type."""

import os

import testlib
from testlib import check

testlib.skip_without_egl()

FAMILY_BOUND = 0.999
OSL_BOUND = 0.995
BASE = {"preset": "lights", "width": 160, "height": 120, "lights": 64, "light_radius": 6}


def job(tech, scene=None, frames=3, capture=3, reference="forward", **extra):
    j = {"technique": tech, "frames": frames, "warmup_frames": 1, "capture_interval": capture,
         "scene": dict(BASE, **(scene or {}))}
    if reference:
        j["reference"] = reference
        j["metrics"] = ["ssim", "pdiff", "psnr"]
    if tech == "osl":
        j["osl"] = {"resolution": "auto"}
    j.update(extra)
    return j


def quality(done):
    """(worst SSIM, PerceptualDiff passed on every capture, every capture identical)."""
    ms = [c.get("metrics", {}) for c in done.get("result", {}).get("captures", [])]
    if not ms:
        return 0.0, False, False
    return (min(m.get("ssim", 0) for m in ms), all(m.get("pdiff", {}).get("pass") for m in ms),
            all(m.get("psnr", {}).get("identical") is True for m in ms))


def matches(d, j, what, bound=FAMILY_BOUND, identical=False, pdiff=True):
    """pdiff: PerceptualDiff must pass too (not for OSL, whose texel
    shading fails it with point lights as well: its bar is SSIM alone)."""
    done = d.run(j)
    ok = check(done.get("status") == "done", "%s runs: %s" % (what, done.get("error")))
    ssim, passed, same = quality(done)
    print("  %-66s SSIM %.6f  PerceptualDiff %s  identical %s" % (what, ssim, passed, same))
    if ok:
        check(ssim >= bound and (passed or not pdiff),
              "%s matches forward: SSIM %.6f >= %s, PerceptualDiff %s" % (what, ssim, bound, passed))
        if identical:
            check(same, "%s is forward's image bit for bit" % what)
    return done


def heat(done):
    caps = done.get("result", {}).get("heatmap", {}).get("captures", [])
    return caps[-1] if caps else {}


def frame_pixels(d, done, name):
    caps = done.get("result", {}).get("captures", [])
    path = os.path.join(d.tmp, name + ".png")
    if not caps or d.download(caps[-1]["url"], path) != 200:
        return None
    return testlib.png_pixels(path)[2]


d = testlib.Daemon()
try:
    status, info = d.json("GET", "/v1/info")
    techs = [t["name"] for t in info.get("techniques", []) if t["name"] not in ("forward", "unlit")]
    check(status == 200 and len(techs) >= 6, "info lists the techniques: %s" % techs)
    culling = [t for t in techs if t != "osl"]

    # Every technique with spots and the sun, moving lights, orbiting camera.
    both = {"light_type": "spot", "sun": True, "dynamic": True}
    for tech in techs:
        matches(d, job(tech, dict(both, camera="orbit")),
                "%s, 64 spots and the sun, orbiting" % tech,
                bound=OSL_BOUND if tech == "osl" else FAMILY_BOUND,
                identical=tech in ("forward_plus", "clustered_forward"),
                pdiff=tech != "osl")
    for tech, opts in (("deferred", {"light_bounds": "scissor_loose"}),
                       ("deferred", {"light_bounds": "volume"}),
                       ("deferred", {"light_bounds": "fullscreen"}),
                       ("tiled_deferred", {"binning": "cpu"}),
                       ("clustered_forward", {"grid": [8, 6, 4], "slices": "linear"})):
        matches(d, job(tech, both, **{tech: opts}), "%s %s, spots and the sun" % (tech, opts))

    # Spots are binned by their cone: fewer evaluations than the same lights
    # as points of the same radius (no sun: it would add 1 to both).
    for tech in ("forward_plus", "clustered_forward", "tiled_deferred"):
        figures = {}
        for kind in ("point", "spot"):
            done = d.run(job(tech, {"lights": 256, "light_type": kind}, reference=None))
            grid = done.get("result", {}).get(tech, {})
            figures[kind] = (heat(done).get("mean", -1),
                             grid.get("lights_per_cell", {}).get("mean", -1),
                             grid.get("overflow", {}).get("frames", -1))
        print("  %-66s points %s  spots %s" % ("%s heat mean, lights per cell, overflow frames" % tech,
                                               figures["point"], figures["spot"]))
        p, s = figures["point"], figures["spot"]
        check(p[0] > 0 and 0 <= s[0] <= 0.6 * p[0],
              "%s bins spots by cone: %.3f evaluations a pixel against %.3f for points" % (tech, s[0], p[0]))
        check(s[1] <= p[1] and s[2] == 0 and p[2] == 0,
              "%s: lights per cell %s vs %s, no overflow" % (tech, s[1], p[1]))

    # The sun alone: in every cell, one evaluation on every surface pixel.
    sun_only = {"lights": 0, "sun": True}
    for tech in culling:
        done = matches(d, job(tech, sun_only), "%s, the sun alone" % tech,
                       identical=tech in ("forward_plus", "clustered_forward"))
        if tech == "visibility_buffer":
            continue  # publishes no heat map (its default loops over every light, as forward)
        h = heat(done)
        check(h.get("max") == 1 and h.get("mean", 0) > 0.5,
              "%s: the sun is one evaluation on every surface pixel: %s" % (tech, h))
    dark = d.run(job("forward", {"lights": 0}, reference=None))
    lit = d.run(job("forward", sun_only, reference=None))
    a, b = frame_pixels(d, dark, "ambient"), frame_pixels(d, lit, "sun")
    if check(a and b, "frames downloaded"):
        surface = [i for i, px in enumerate(a) if any(px)]
        brighter = sum(1 for i in surface if sum(b[i]) > sum(a[i]))
        print("  sun: %d of %d surface pixels brighter than ambient alone" % (brighter, len(surface)))
        check(len(surface) > 5000 and brighter >= 0.9 * len(surface),
              "the sun lights every surface facing it: %d of %d" % (brighter, len(surface)))
        sd = lit.get("result", {}).get("scene", {}).get("lights", {})
        check(sd.get("by_type") == {"point": 0, "spot": 0, "directional": 1} and
              sd.get("per_object_at_frame_0", {}).get("mean") == 1.0,
              "described: one directional light reaching every object: %s" % sd)

    # Spot cones limit the lit area.
    areas = {}
    for kind in ("point", "spot"):
        done = d.run(job("forward", {"lights": 16, "light_type": kind}, reference=None))
        px = frame_pixels(d, done, kind)
        if px and a:
            areas[kind] = sum(1 for i in range(len(a)) if max(abs(x - y) for x, y in zip(px[i], a[i])) > 2)
    print("  lit pixels, 16 lights: %s" % areas)
    check(len(areas) == 2 and 0 < areas["spot"] < 0.6 * areas["point"],
          "spot cones limit the lit area: %s" % areas)

    # MSAA: the per-sample paths shade and bin them alike.
    matches(d, job("clustered_forward", both, msaa=4), "clustered_forward, msaa 4, spots and the sun",
            identical=True)
    matches(d, job("clustered_deferred", both, msaa=4), "clustered_deferred, msaa 4, spots and the sun")

    # The physically based model shades them the same way everywhere.
    for tech in ("clustered_deferred", "forward_plus"):
        matches(d, job(tech, both, look={"lighting": "pbr"}), "%s, PBR, spots and the sun" % tech)

    # Shadows: spots with omni maps, the sun reported unshadowed.
    shadows = {"look": {"shadows": {"atlas": 1024}}}
    done = matches(d, job("deferred", both, **shadows), "deferred with shadows, spots and the sun")
    sh = done.get("result", {}).get("shadows", {})
    print("  shadows: mapped %s, directional %s, skipped %s"
          % (sh.get("lights_mapped"), sh.get("directional"), sh.get("skipped_lights")))
    check(sh.get("directional", {}).get("mapped") == 1 and
          sh.get("skipped_lights", {}).get("directional") == 0 and
          sh.get("lights_mapped", {}).get("max", 0) > 0,
          "spots get omni maps, the sun its own: %s" % sh.get("directional"))
    # The sun's map, and a spot's omni map (of which only the faces its cone
    # reaches are drawn): the sphere preset (a sphere of radius 0.8 at the
    # origin on the ground at y -0.8, its one light 3 units above it) lit by
    # the sun alone, then by its light as a spot pointing down, ray-cast here
    # as e2e_pbr does for a point light: the ground the sphere hides from
    # the light is darker, nothing else changes, no acne on its lit side.
    for what, scene, light_at in (("the sun", {"lights": 0, "sun": True}, None),
                                  ("a spot", {"light_type": "spot", "spot_angle_deg": 40},
                                   [0.0, 3.0, 0.0])):
        pixels, sun_dir, camera = {}, None, {}
        for on in (False, True):
            done = d.run({"technique": "forward", "frames": 1, "warmup_frames": 0,
                          "capture_interval": 1,
                          "look": {"lighting": "pbr", "shadows": {"pcf": 1} if on else False},
                          "scene": dict({"preset": "sphere", "width": 160, "height": 120,
                                         "roughness": 0.6}, **scene)})
            check(done.get("status") == "done", "%s shadow job runs: %s" % (what, done.get("error")))
            pixels[on] = frame_pixels(d, done, "shadow-%s-%d" % (what[-3:], on))
            r = done.get("result", {})
            camera = r.get("scene", {}).get("camera", {})
            sun_dir = r.get("scene", {}).get("lights", {}).get("sun_light", {}).get("direction")
            if on and light_at:
                check(r.get("shadows", {}).get("faces_per_frame") == 1.0,
                      "a spot pointing down draws one face: %s" % r.get("shadows", {}).get("faces_per_frame"))
        if not check(pixels[False] and pixels[True] and camera and (sun_dir or light_at),
                     "%s shadow frames" % what):
            continue
        towards = (testlib.towards_point(light_at) if light_at else
                   (lambda p: ([-c for c in sun_dir], float("inf"))))
        core, core_dark, outside_changed, lit_changed = testlib.sphere_shadow_counts(
            camera, pixels[False], pixels[True], 160, 120, towards)
        print("  %s's shadow: %d of %d ground pixels in the core darker, %d changed outside, "
              "%d changed on the lit side" % (what, core_dark, core, outside_changed, lit_changed))
        check(core > 50 and core_dark == core,
              "the ground the sphere hides from %s is in shadow: %d of %d" % (what, core_dark, core))
        check(outside_changed == 0, "%s: no pixel changes where no shadow can fall: %d"
              % (what, outside_changed))
        check(lit_changed == 0, "%s: no acne on the sphere's lit side: %d" % (what, lit_changed))

    # The options: spec, errors, sweeps.
    spec = lit.get("spec", {}).get("scene", {})
    check(spec.get("light_type") == "point" and spec.get("sun") is True
          and spec.get("spot_angle_deg") == 30.0, "spec written back: %s" % spec)
    for bad, field in (({"light_type": "directional"}, "scene.light_type"),
                       ({"light_type": "area"}, "scene.light_type"),
                       ({"spot_angle_deg": 90}, "scene.spot_angle_deg"),
                       ({"spot_angle_deg": "wide"}, "scene.spot_angle_deg"),
                       ({"sun": 1}, "scene.sun")):
        testlib.rejects(d, job("forward", bad, reference=None), field)
    status, sub = d.json("POST", "/v1/sweeps", {
        "base": job("clustered_forward", {"lights": 32}, frames=1, capture=1, reference=None),
        "vary": {"scene.light_type": ["point", "spot"], "scene.sun": [False, True]}})
    sw = d.wait_sweep(sub["id"]) if status == 202 else {}
    rows = sw.get("points", [])
    # Each scene gets its own forward reference row.
    mine = sorted((r["values"].get("scene.light_type"), r["values"].get("scene.sun"))
                  for r in rows if r.get("technique") == "clustered_forward")
    check(sw.get("status") == "done" and len(rows) == 8 and
          mine == [("point", False), ("point", True), ("spot", False), ("spot", True)],
          "a sweep varies scene.light_type and scene.sun: %s %s" % (status, sw.get("error", sub)))
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_light_types")
