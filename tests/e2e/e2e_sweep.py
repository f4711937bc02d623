"""Sweeps end to end: a grid over async_distance on a small dynamic OSL
scene whose table behaves as the schedule says, a find that returns the
light speed at which PerceptualDiff starts failing, cancelling with the
finished points kept, and bad sweeps answered 400 naming the field."""

import os
import time
import xml.etree.ElementTree as ET

import testlib
from testlib import check

testlib.skip_without_egl()
BASE = {"technique": "osl", "frames": 8, "warmup_frames": 2, "async_distance": 20,
        "osl": {"resolution": "auto"}, "scene": {"dynamic": True, "width": 200, "height": 150}}


def post(d, body):
    status, reply = d.json("POST", "/v1/sweeps", body)
    if status != 202:
        raise RuntimeError("sweep refused: %d %s" % (status, reply))
    return reply["id"]


def wait(d, sweep_id):
    return d.wait_sweep(sweep_id)


d = testlib.Daemon()
try:
    # A grid over async_distance: 0 and 80 both reshade every object every
    # frame here (no object is 80 units away), 5 leaves them stale for 7 to
    # 11 frames: the table must show exactly that.
    sw = wait(d, post(d, {"base": BASE, "vary": {"async_distance": [0, 5, 80]}}))
    check(sw["status"] == "done", "grid sweep done: %s" % sw.get("error"))
    rows = [r for r in sw["points"] if r["technique"] == "osl"]
    check(len(rows) == 3 and [r["values"]["async_distance"] for r in rows] == [0, 5, 80], "one row per value")
    ref = [r for r in sw["points"] if r["technique"] == "forward"]
    check(len(sw["points"]) == 4 and len(ref) == 1 and ref[0]["values"] == {"technique": "forward"} and
          ref[0]["frame_ms"]["median"] > 0 and "worst_ssim" not in ref[0],
          "the reference technique is timed once beside the grid, not judged: %s" % ref)
    for r in rows:
        check(r["status"] == "done" and r["frame_ms"]["median"] > 0 and len(r["frame_ms"]["ci95"]) == 2,
              "row has a median frame time with its interval: %s" % r.get("frame_ms"))
        check("worst_ssim" in r and "worst_flip" in r and "pdiff_failed_captures" in r, "row has quality")
    check(rows[0]["worst_ssim"] == rows[2]["worst_ssim"], "d 0 and d 80 give the same image")
    check(rows[1]["worst_ssim"] < rows[0]["worst_ssim"] and rows[1]["worst_flip"] > rows[0]["worst_flip"],
          "stale shading at d 5 costs quality: SSIM %s vs %s" % (rows[1]["worst_ssim"], rows[0]["worst_ssim"]))
    largest = sw.get("result", {}).get("largest_pdiff_pass", {})
    passing = [r["values"]["async_distance"] for r in rows if r.get("pdiff_failed_captures") == 0]
    check(largest.get("param") == "async_distance" and largest.get("value") == (max(passing) if passing else None),
          "largest async distance that passes PerceptualDiff: %s (passing %s)" % (largest, passing))
    grid_id = sw["id"]
    for name in ("speed_accuracy", "time_vs_param", "distribution"):
        svg, png = os.path.join(d.tmp, name + ".svg"), os.path.join(d.tmp, name + ".png")
        check(d.download("/v1/sweeps/%s/charts/%s.svg" % (grid_id, name), svg) == 200, "%s.svg served" % name)
        check(d.download("/v1/sweeps/%s/charts/%s.png" % (grid_id, name), png) == 200, "%s.png served" % name)
        try:
            root = ET.parse(svg).getroot()
            check(root.tag.endswith("svg") and len(list(root.iter())) > 20, "%s.svg is an SVG drawing" % name)
        except ET.ParseError as e:
            check(False, "%s.svg parses: %s" % (name, e))
        info = testlib.png_info(png)
        check(info and info["width"] == 900 and info["height"] >= 560 and info["colours"] > 5,
              "%s.png is a 900-wide chart, 560 high plus its notes: %s" % (name, info))
    check(d.download("/v1/sweeps/%s/charts/speed_accuracy.svg?y=flip&series=cpu_ms" % grid_id,
                     os.path.join(d.tmp, "flip.svg")) == 200, "FLIP and cpu_ms variants")
    check(d.json("GET", "/v1/sweeps/%s/charts/nope.svg" % grid_id)[0] == 404, "unknown chart is 404")
    check(d.json("GET", "/v1/sweeps/%s/charts/time_vs_param.svg?series=fps" % grid_id)[0] == 400,
          "bad series is 400")
    job = d.json("GET", "/v1/jobs/" + rows[1]["job"])[1]
    check(d.download("/v1/jobs/%s/charts/distribution.png" % rows[1]["job"],
                     os.path.join(d.tmp, "job.png")) == 200, "a job's distribution chart")
    check(job["status"] == "done" and job["spec"]["reference"] == "forward", "each point is a job with a reference")

    # Breaking point: the largest light speed at which OSL (d 20) still passes.
    sw = wait(d, post(d, {"base": BASE, "find": {"param": "scene.light_speed", "from": 0, "to": 16,
                                                  "while": "pdiff_pass", "steps": 7}}))
    check(sw["status"] == "done", "find done: %s" % sw.get("error"))
    bp = sw.get("result", {}).get("breaking_point", {})
    check(bp.get("param") == "scene.light_speed" and bp.get("criterion") == "pdiff_pass", "breaking point named")
    check(bp.get("outcome") == "boundary" and 0 <= bp["value"] < bp["first_failing"] <= 16,
          "a boundary inside the range: %s" % bp)
    probes = sw["points"]
    check(len(probes) == bp["probes"] and all("criterion_holds" in p for p in probes),
          "every probe is in the table with its verdict")
    holds = {p["values"]["scene.light_speed"]: p["criterion_holds"] for p in probes}
    check(holds.get(0) is True and holds.get(16) is False, "holds with still lights, fails when fast: %s" % holds)
    check(all(v is True for k, v in holds.items() if k <= bp["value"]) and
          all(v is False for k, v in holds.items() if k >= bp["first_failing"]), "probes agree with the boundary")

    # Cancel: the finished points stay readable.
    long_id = post(d, {"base": dict(BASE, frames=60), "vary": {"scene.lights": [1, 2, 3, 4, 5, 6, 7, 8]}})
    deadline = time.time() + 120
    while d.json("GET", "/v1/sweeps/" + long_id)[1]["progress"]["points_done"] < 1 and time.time() < deadline:
        time.sleep(0.2)
    status, body = d.json("DELETE", "/v1/sweeps/" + long_id)
    check(status in (200, 202), "cancel accepted")
    sw = wait(d, long_id)
    check(sw["status"] == "cancelled" and 1 <= len(sw["points"]) < 8, "cancelled, finished points kept: %d" % len(sw["points"]))
    check(d.json("DELETE", "/v1/sweeps/" + long_id)[0] == 409, "cancelling a finished sweep is 409")
    listed = [s["id"] for s in d.json("GET", "/v1/sweeps")[1]["sweeps"]]
    check(long_id in listed and len(listed) == 3, "list has the sweeps")

    # Bad sweeps name the field.
    for body, field in (({"base": BASE, "vary": {"async_distance": list(range(16)), "scene.lights": list(range(1, 18))}}, "vary"),
                        ({"base": BASE, "vary": {"scene.lightz": [1]}}, "vary.scene.lightz"),
                        ({"base": BASE, "vary": {"async_distance": [0, "far"]}}, "vary.async_distance[1]"),
                        ({"base": BASE, "find": {"param": "technique", "from": 0, "to": 1, "while": "pdiff_pass"}}, "find.param"),
                        ({"base": BASE, "find": {"param": "async_distance", "from": 0, "to": 1, "while": "nice"}}, "find.while"),
                        ({"base": {"frames": -1}, "vary": {"frames": [1]}}, "base"),
                        ({"vary": {"frames": [1]}}, "base")):
        code, reply = d.json("POST", "/v1/sweeps", body)
        check(code == 400 and reply.get("error", {}).get("field") == field,
              "%s -> 400 naming %s (got %d %s)" % (str(body)[:80], field, code, reply))
    check(d.json("GET", "/v1/sweeps/99999999-999999-9999")[0] == 404, "unknown sweep is 404")
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_sweep")
