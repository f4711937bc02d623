"""The technique contract, over the registry as /v1/info describes it, so a
technique added later is tested without new test code:
- conformance: every technique but unlit, at default options, agrees with
  forward under the same look (SSIM bound), on the grid (still lights) and
  on the lights preset with moving lights and an orbiting camera, runs
  every pass it declares plus
  the harness's resolve, and reports them in the result and timings.csv;
- options: /v1/info documents each option (type, default, rule); the defaults
  are accepted and come back in the spec unchanged; a bad value of each
  option answers 400 naming "<technique>.<option>";
- the look: Blinn-Phong and PBR change the image against Phong, a technique
  with Blinn-Phong still agrees with forward under the same look, every
  technique with PBR agrees with forward with PBR; a 16-bit HDR target
  runs."""

import os

import testlib
from testlib import check

testlib.skip_without_egl()

SSIM_BOUND = 0.995
SCENE = {"width": 160, "height": 120, "dynamic": True}
# Frame 2 captured: a timed frame after the harness's own and the warm-up
# has moved the lights and the camera (every SSIM here is frame 4's to the
# fifth digit, OSL's orbit 0.99937 against 0.99946).
JOB = {"frames": 2, "warmup_frames": 1, "capture_interval": 2, "scene": SCENE}
# Still lights for the checks at OSL's defaults (the defaults and PBR; 256
# texels an object before auto tiles became the default): OSL shades its atlas once instead of every frame (3 s a
# job instead of 10 here). Moving lights are checked on every technique in
# the orbiting-camera run.
STILL = dict(SCENE, dynamic=False)
# Options for the checks past the defaults one (moving camera, Blinn-Phong),
# which test that every pass sees the camera and the look, not the default
# options again: OSL at its default 256 texels an object costs 90 to 150 s a
# job on llvmpipe, with "auto" tiles under 2 s (SSIM 0.9989 and 0.9992).
# PBR keeps the defaults: OSL's undersampled GGX highlights drop to SSIM
# 0.9945 at 128 texels, and the check is that the default agrees (auto
# tiles at 2 texels a pixel under PBR: 0.9965; at 1, 0.987).
CHEAP = {"osl": {"resolution": "auto"}}


def bad_value(opt):
    """A value the option's rule refuses, for each kind /v1/info names."""
    kind = opt["type"]
    if kind == "integer":
        return int(opt["max"]) + 1
    if kind == "number":
        return "not a number"
    if kind == "boolean":
        return "yes"
    if kind == "choice":
        return "no_such_choice"
    if kind == "power_of_two_or_auto":
        return 3
    if kind == "integer_list":
        return []
    raise AssertionError("unknown option type %s" % kind)


def nest(path, value):
    """{"a": {"b": value}} for "a.b"."""
    head, _, rest = path.partition(".")
    return {head: nest(rest, value) if rest else value}


d = testlib.Daemon()
try:
    status, info = d.json("GET", "/v1/info")
    techs = info.get("techniques", [])
    names = [t.get("name") for t in techs]
    check(status == 200 and {"forward", "unlit", "osl"} <= set(names), "info lists techniques: %s" % names)

    sweepable = info.get("sweepable", {})
    check(sweepable.get("scene.lights") == "integer" and sweepable.get("osl.resolution") == "choice",
          "info lists what sweeps may vary: %s" % sorted(sweepable)[:8])

    for t in techs:
        name = t["name"]
        for oname in t.get("options", {}):
            check("%s.%s" % (name, oname) in sweepable, "%s.%s is sweepable" % (name, oname))
        check(t.get("summary") and t.get("passes"), "%s: summary and passes documented" % name)
        for oname, opt in t.get("options", {}).items():
            check(all(k in opt for k in ("type", "default", "rule", "summary")),
                  "%s.%s documented: %s" % (name, oname, opt))

        # Defaults: accepted, and the spec gives them back unchanged.
        defaults = {}
        for oname, opt in t.get("options", {}).items():
            for k, v in nest(oname, opt["default"]).items():
                if isinstance(v, dict):
                    defaults.setdefault(k, {}).update(v)
                else:
                    defaults[k] = v
        job = dict(JOB, technique=name, scene=STILL, **{name: defaults})
        if name != "unlit":
            job["reference"] = "forward"
        done = d.run(job)
        check(done.get("status") == "done", "%s at defaults runs: %s" % (name, done.get("error")))
        check(done.get("spec", {}).get(name) == defaults,
              "%s: defaults round-trip (%s vs %s)" % (name, done.get("spec", {}).get(name), defaults))
        result = done.get("result", {})
        sections = list(result.get("gpu_sections_ms", {}))
        check(sections == t["passes"] + ["resolve"],
              "%s: result times every declared pass, then resolve: %s" % (name, sections))
        status, _, csv = d.request("GET", "/v1/jobs/%s/timings.csv" % done.get("id"))
        header = csv.decode().splitlines()[0].split(",") if status == 200 else []
        check(header[4:] == ["gpu_%s_ms" % p for p in t["passes"] + ["resolve"]] + ["drawn_whole"],
              "%s: timings.csv has a column per pass, then drawn_whole: %s" % (name, header))
        if name != "unlit":
            ssim = result.get("quality", {}).get("worst_ssim", {}).get("value", 0)
            check(ssim >= SSIM_BOUND, "%s agrees with forward: SSIM %.5f >= %s" % (name, ssim, SSIM_BOUND))
            # The many-lights scene under a moving camera: the frame block's
            # camera reaches every pass of the technique.
            moving = dict(JOB, technique=name, reference="forward",
                          scene=dict(SCENE, preset="lights", lights=64, camera="orbit"))
            if name in CHEAP:
                moving[name] = CHEAP[name]
            done = d.run(moving)
            ssim = done.get("result", {}).get("quality", {}).get("worst_ssim", {}).get("value", 0)
            check(done.get("status") == "done" and ssim >= SSIM_BOUND,
                  "%s agrees with forward on lights with an orbiting camera: SSIM %.5f (%s)"
                  % (name, ssim, done.get("error")))

        # A bad value of each option is refused, naming it.
        for oname, opt in t.get("options", {}).items():
            testlib.rejects(d, dict(JOB, technique=name, **{name: nest(oname, bad_value(opt))}),
                            "%s.%s" % (name, oname))
        testlib.rejects(d, dict(JOB, **{name: {"no_such_option": 1}}), "%s.no_such_option" % name)

    # The look: the lighting model changes the image, and every technique is
    # scored against forward under the same look.
    paths = {}
    for lighting in ("phong", "blinn_phong", "pbr"):
        done = d.run(dict(JOB, technique="forward", look={"lighting": lighting}))
        check(done.get("spec", {}).get("look", {}).get("lighting") == lighting, "look in the spec")
        paths[lighting] = os.path.join(d.tmp, lighting + ".png")
        d.download(done["result"]["captures"][-1]["url"], paths[lighting])
    diff = testlib.png_diff(paths["phong"], paths["blinn_phong"])
    check(diff and diff["max_abs"] > 0, "Blinn-Phong differs from Phong: %s" % diff)
    done = d.run(dict(JOB, technique="osl", reference="forward", look={"lighting": "blinn_phong"}, **CHEAP))
    ssim = done.get("result", {}).get("quality", {}).get("worst_ssim", {}).get("value", 0)
    check(ssim >= SSIM_BOUND, "osl with Blinn-Phong agrees with forward with Blinn-Phong: %.5f" % ssim)
    diff = testlib.png_diff(paths["phong"], paths["pbr"])
    check(diff and diff["max_abs"] > 0, "PBR differs from Phong: %s" % diff)
    # Every technique but unlit, with PBR, agrees with forward with PBR, on
    # the many-lights scene (varied materials: a quarter of them metallic).
    for name in names:
        if name in ("forward", "unlit"):
            continue
        done = d.run(dict(JOB, technique=name, reference="forward", look={"lighting": "pbr"},
                          scene=dict(STILL, preset="lights", lights=64)))
        ssim = done.get("result", {}).get("quality", {}).get("worst_ssim", {}).get("value", 0)
        check(done.get("status") == "done" and ssim >= SSIM_BOUND,
              "%s with PBR agrees with forward with PBR: SSIM %.5f (%s)"
              % (name, ssim, done.get("error")))
    done = d.run(dict(JOB, technique="forward", look={"hdr": "rgba16f"}))
    check(done.get("status") == "done" and done["result"].get("look", {}).get("hdr") == "rgba16f",
          "a 16-bit HDR target runs: %s" % done.get("error"))
    testlib.rejects(d, dict(JOB, look={"lighting": "toon"}), "look.lighting")
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_techniques")
