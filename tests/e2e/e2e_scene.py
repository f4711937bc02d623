"""The general scene end to end: the lights preset renders with forward,
unlit and OSL; a moving camera changes the picture from frame to frame while
every frame stays a pure function of its index (two runs, or different
warm-ups, give identical captures); "auto" tessellation and the spec's
new fields come back in the job; bad scene options answer 400 naming the
field."""

import os

import testlib
from testlib import check

testlib.skip_without_egl()

SMALL = {"preset": "lights", "lights": 256, "width": 160, "height": 120}


def captures(d, job, name):
    """Runs job; returns (job, [paths of its captures])."""
    done = d.run(job)
    check(done.get("status") == "done", "%s done: %s" % (name, done.get("error")))
    paths = []
    for c in done.get("result", {}).get("captures", []):
        path = os.path.join(d.tmp, "%s-%d.png" % (name, c["frame"]))
        check(d.download(c["url"], path) == 200, "%s frame %d downloads" % (name, c["frame"]))
        paths.append(path)
    return done, paths


def identical(a, b):
    diff = testlib.png_diff(a, b)
    return diff is not None and diff["max_abs"] == 0


d = testlib.Daemon()
try:
    moving = dict(SMALL, camera={"path": "orbit", "period": 40})
    base = {"frames": 10, "warmup_frames": 2, "capture_interval": 5}
    shots = {}
    for tech in ("forward", "unlit"):
        job, (f5, f10) = captures(d, dict(base, technique=tech, scene=moving), tech)
        r = job.get("result", {})
        check(r.get("instances") == 145 and r.get("lights") == 256,
              "%s: 144 objects and the ground, 256 lights (%s, %s)" % (tech, r.get("instances"), r.get("lights")))
        check(not identical(f5, f10), "%s: the orbiting camera changes frame 5 to frame 10" % tech)
        _, (g5, g10) = captures(d, dict(base, technique=tech, scene=moving), tech + "-again")
        check(identical(f5, g5) and identical(f10, g10), "%s: a second run gives identical captures" % tech)
        _, (_, h10) = captures(d, dict(base, technique=tech, scene=moving, warmup_frames=0),
                               tech + "-nowarmup")
        check(identical(f10, h10), "%s: frame 10 is the same after 0 or 2 warm-up frames" % tech)
        shots[tech] = f10
        spec = job.get("spec", {}).get("scene", {})
        check(spec.get("camera") == {"path": "orbit", "period": 40} and spec.get("preset") == "lights"
              and spec.get("light_layout") == "uniform" and spec.get("materials") == "varied"
              and spec.get("light_radius") == 4.0,
              "%s: the scene comes back with its defaults filled in: %s" % (tech, spec))
    diff = testlib.png_diff(shots["forward"], shots["unlit"])
    check(diff and diff["max_abs"] > 0, "forward's lights show against unlit: %s" % diff)

    # Still camera and still lights: frames 5 and 10 are the same picture,
    # so the difference above is the camera's.
    _, (s5, s10) = captures(d, dict(base, technique="forward", scene=SMALL), "still")
    check(identical(s5, s10), "a static camera over still lights draws the same frame")

    # The flythrough renders too, and differs from the orbit.
    _, (_, fly10) = captures(d, dict(base, technique="forward",
                                     scene=dict(SMALL, camera={"path": "flythrough", "period": 40})), "fly")
    check(not identical(fly10, shots["forward"]), "the flythrough sees another picture")

    # OSL lights the ground plane too (a third mesh with its own UV chart):
    # close to forward on average (a 64-texel tile blurs the highlights of a
    # 48-unit ground, so single pixels may differ a lot; a broken chart or
    # mesh index moves it several times over).
    still = dict(base, frames=2, capture_interval=2, warmup_frames=0,
                 scene=dict(SMALL, lights=32, width=320, height=240))
    _, (fwd,) = captures(d, dict(still, technique="forward"), "osl-ref")
    for res in (64, "auto"):
        job, (osl,) = captures(d, dict(still, technique="osl", osl={"resolution": res}), "osl-%s" % res)
        diff = testlib.png_diff(fwd, osl)
        check(diff and max(diff["mean_abs"]) <= 1.0,
              "osl %s on the lights preset within its sampling error of forward: %s" % (res, diff))
        check(job.get("result", {}).get("osl", {}).get("initial_shading", {}).get("objects") == 145,
              "osl %s shades all 145 objects, the ground included" % res)

    # "auto" tessellation models no more than a 160x120 image needs.
    fixed = d.run(dict(base, technique="unlit", capture_interval=0, scene=SMALL))
    auto = d.run(dict(base, technique="unlit", capture_interval=0,
                      scene=dict(SMALL, sphere_segments="auto")))
    check(auto.get("status") == "done" and auto["spec"]["scene"]["sphere_segments"] == "auto",
          "sphere_segments auto runs and is written back")
    check(0 < auto.get("result", {}).get("triangles_per_frame", 0) <
          fixed.get("result", {}).get("triangles_per_frame", 0),
          "auto draws fewer triangles than 32 segments at 160x120 (%s vs %s)"
          % (auto.get("result", {}).get("triangles_per_frame"), fixed.get("result", {}).get("triangles_per_frame")))

    # Many lights are accepted; bad values name their field.
    check(d.run(dict(base, technique="unlit", frames=1, capture_interval=0,
                     scene=dict(SMALL, lights=16384)))["status"] == "done", "16,384 lights run")
    for scene, field in (({"lights": 70000}, "scene.lights"),
                         ({"light_layout": "spiral"}, "scene.light_layout"),
                         ({"light_radius": 0}, "scene.light_radius"),
                         ({"camera": "drone"}, "scene.camera"),
                         ({"camera": {"path": "drone"}}, "scene.camera.path"),
                         ({"camera": {"path": "orbit", "period": 0}}, "scene.camera.period"),
                         ({"sphere_segments": "fine"}, "scene.sphere_segments"),
                         ({"materials": "shiny"}, "scene.materials"),
                         ({"roughness": 2}, "scene.roughness")):
        testlib.rejects(d, {"scene": scene}, field)
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_scene")
