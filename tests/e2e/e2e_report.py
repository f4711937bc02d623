"""Report pages in a real browser: headless Chromium loads a sweep's and a
job's report.html from the daemon, logs no console message, and the
screenshot shows the page. The pages are self-contained: every image is
embedded, nothing is fetched."""

import os
import re
import shutil
import subprocess
import tempfile

import testlib
from testlib import check

testlib.skip_without_egl()
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
BASE = {"technique": "osl", "frames": 6, "warmup_frames": 1, "osl": {"resolution": "auto"},
        "scene": {"dynamic": True, "width": 160, "height": 120}}


def browse(url, shot):
    profile = tempfile.mkdtemp(prefix="shadebench-chromium-")
    try:
        # The flags keep headless Chromium off the network and the GPU.
        out = subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                              "--no-first-run", "--disable-background-networking",
                              "--disable-component-update", "--disable-sync",
                              "--user-data-dir=" + profile, "--enable-logging=stderr", "--v=0",
                              "--window-size=1280,2000", "--screenshot=" + shot, url],
                             capture_output=True, text=True, timeout=180)
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    console = [l for l in out.stderr.splitlines() if "CONSOLE" in l]
    return out.returncode, console


check(CHROMIUM is not None, "chromium is installed (tools/setup installs it)")
d = testlib.Daemon()
try:
    status, reply = d.json("POST", "/v1/sweeps", {"base": BASE, "vary": {"async_distance": [0, 20]}})
    sweep_id = reply["id"]
    sw = d.wait_sweep(sweep_id)
    check(sw["status"] == "done", "sweep done")
    job_id = sw["points"][1]["job"]

    # The thesis preset, cut down to fit a CPU renderer: 4 points at a
    # quarter of its size (270x180, OSL's tiles 64 texels a side: the same
    # texels per pixel; at 1080x720 and 256 texels OSL shades a 33-million-
    # texel atlas on each run's first frame, about 50 CPU seconds on llvmpipe
    # here), each run a single timed frame, repeated twice so that the tables
    # are over runs. The preset's own settings at full size, and each scale's,
    # are tests/unit/test_sweep's.
    status, reply = d.json("POST", "/v1/sweeps", {"preset": "thesis", "scale": 0.25, "frames": 1,
                                                  "warmup_frames": 0, "repeat": 2})
    check(status == 202, "thesis preset accepted: %s" % reply)
    thesis_id = reply["id"]
    th = d.wait_sweep(thesis_id)
    check(th["status"] == "done" and len(th["points"]) == 4, "thesis preset ran its 4 points: %s" % th.get("error"))
    combos = {(p["technique"], p["values"]["scene.dynamic"]) for p in th["points"]}
    check(combos == {("forward", False), ("forward", True), ("osl", False), ("osl", True)},
          "forward and OSL, still and moving lights")
    check(all(p["wall_s"]["runs"] == 2 and p["worst_ssim"] is not None for p in th["points"]),
          "every point repeated twice and judged")
    # Whole tiles with 10 lights show forward's image with still lights, as
    # the thesis found (SSIM 0.99991 to 0.99994, PerceptualDiff passing; here
    # 0.99998 at 270x180, 2026-11-27): e2e_osl holds 256 to forward with 2.
    still_osl = [p for p in th["points"] if p["technique"] == "osl" and not p["values"]["scene.dynamic"]]
    check(still_osl and still_osl[0]["worst_ssim"] >= 0.9999 and still_osl[0]["pdiff_failed_captures"] == 0,
          "the thesis's OSL with still lights: SSIM >= 0.9999, PerceptualDiff passing: %s" % still_osl)
    osl_job = d.json("GET", "/v1/jobs/" + [p for p in th["points"] if p["technique"] == "osl"][0]["job"])[1]
    check(osl_job["spec"]["async_distance"] == 20 and osl_job["spec"]["osl"]["resolution"] == 64 and
          osl_job["spec"]["osl"]["visibility"] == "all" and
          osl_job["spec"]["metrics"]["pdiff"]["fov"] == 22.6 and osl_job["spec"]["scene"]["width"] == 270 and
          osl_job["spec"]["scene"]["height"] == 180 and
          osl_job["spec"]["warmup_frames"] == 0 and osl_job["spec"]["frames"] == 1,
          "the thesis's settings at scale 0.25: async 20, 64 texels, PerceptualDiff at 22.6 degrees, "
          "270x180")
    for body, field in (({"preset": "sponza"}, "preset"), ({"preset": "thesis", "frames": 0}, "frames"),
                        ({"preset": "thesis", "warmup_frames": -1}, "warmup_frames"),
                        ({"preset": "thesis", "lights": 3}, "lights"),
                        ({"preset": "thesis", "scale": 0.3}, "scale")):
        code, r = d.json("POST", "/v1/sweeps", body)
        check(code == 400 and r.get("error", {}).get("field") == field, "%s -> 400 naming %s" % (body, field))

    for kind, path in (("sweep", "/v1/sweeps/%s/report.html" % sweep_id),
                       ("job", "/v1/jobs/%s/report.html" % job_id),
                       ("thesis", "/v1/sweeps/%s/report.html" % thesis_id)):
        status, headers, raw = d.request("GET", path)
        html = raw.decode()
        check(status == 200 and headers.get("Content-Type", "").startswith("text/html"), "%s report served" % kind)
        check("<table>" in html, "%s report has its table" % kind)
        sources = re.findall(r'(?:src|href)="([^"]*)"', html)
        check(sources and all(s.startswith("data:image/png;base64,") for s in sources),
              "%s report embeds everything (%d images, no external links)" % (kind, len(sources)))
        check("<script" not in html, "%s report has no scripts" % kind)
        check("&quot;technique&quot;" in html and "<pre>" in html, "%s report shows the exact JSON" % kind)
        if kind == "sweep":
            check(html.count("data:image/png") >= 4 + 2 * 4, "charts and thumbnails of both points")
        if kind == "thesis":
            check("experiment on this device" in html and "OSL (64, async 20)" in html and
                  "moving lights" in html and "still lights" in html, "the thesis's tables")
            check("scale 0.25): 270x180, OSL's tiles 64 texels" in html,
                  "the thesis report says it ran smaller than the thesis")
            # 4 charts; per point the frame, the reference and the SSIM map (the
            # thesis computed no FLIP, so there is no FLIP map).
            check('alt="frame-time distributions"' in html and html.count("data:image/png") >= 4 + 4 * 3,
                  "timing distributions and captures of both techniques")
        if CHROMIUM:
            shot = os.path.join(d.tmp, kind + ".png")
            rc, console = browse(d.base + path, shot)
            check(rc == 0, "chromium loaded the %s report" % kind)
            check(not console, "no console messages: %s" % console[:3])
            info = testlib.png_info(shot) if os.path.exists(shot) else None
            check(info and info["width"] == 1280 and info["colours"] > 50,
                  "the %s screenshot shows the page: %s" % (kind, info))
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_report")
