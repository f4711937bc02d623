"""Every bad-input rule over HTTP: each rejection is JSON naming the field,
the daemon survives all of it (random bodies included), and a good job
still runs afterwards."""

import random
import socket
import time

import testlib
from testlib import check

testlib.skip_without_egl()

SMALL = {"frames": 4, "warmup_frames": 0, "scene": {"width": 64, "height": 48}}


rejected = testlib.rejects

d = testlib.Daemon()
try:
    # Malformed and mistyped bodies.
    rejected(d, "", "body", what="empty body")
    rejected(d, "{", "body", what="truncated JSON")
    rejected(d, "[]", "body", what="array body")
    rejected(d, '{"frames": 3, "frames": 4}', "body", what="duplicate key")
    rejected(d, {"technique": "no_such_technique"}, "technique")
    rejected(d, {"technique": None}, "technique")
    rejected(d, {"frames": "300"}, "frames")
    rejected(d, {"frames": 0}, "frames")
    rejected(d, {"frames": 2.5}, "frames")
    rejected(d, {"warmup_frames": -1}, "warmup_frames")
    rejected(d, {"capture_interval": True}, "capture_interval")
    rejected(d, {"frames": 5, "capture_interval": 6}, "capture_interval")
    rejected(d, {"async_distance": -3}, "async_distance")
    rejected(d, {"scene": []}, "scene")
    rejected(d, {"scene": {"width": 15}}, "scene.width")
    rejected(d, {"scene": {"width": 8193}}, "scene.width")
    rejected(d, {"scene": {"height": "720"}}, "scene.height")
    rejected(d, {"scene": {"lights": 70000}}, "scene.lights")
    rejected(d, {"scene": {"dynamic": 1}}, "scene.dynamic")
    rejected(d, {"scene": {"preset": "sponza"}}, "scene.preset")
    rejected(d, {"osl": {"resolution": 300}}, "osl.resolution")
    # Unknown fields (typos) are named, with a suggestion.
    code, reply = d.json("POST", "/v1/jobs", {"technqiue": "forward"})
    check(code == 400 and reply["error"]["field"] == "technqiue"
          and "technique" in reply["error"]["message"], "typo named with suggestion: %s" % reply)
    rejected(d, {"scene": {"lihgts": 3}}, "scene.lihgts")

    # Bodies over 64 KiB: 413, whether announced by Content-Length or not.
    big = '{"technique":"forward","pad":"' + "x" * 70000 + '"}'
    code, reply = d.json("POST", "/v1/jobs", big)
    check(code == 413 and reply["error"]["field"] == "body", "64 KiB+ body is 413: %d" % code)
    s = socket.create_connection(("127.0.0.1", d.port), timeout=30)
    s.sendall(b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n")
    chunk = b"x" * 8192
    for _ in range(10):
        s.sendall(b"%x\r\n%s\r\n" % (len(chunk), chunk))
    s.sendall(b"0\r\n\r\n")
    head = s.recv(4096)
    s.close()
    check(head.startswith(b"HTTP/1.1 413"), "chunked 80 KiB body is 413: %r" % head[:40])

    # Routes, ids and methods.
    check(d.json("GET", "/v1/jobs/99999999-999999-9999")[0] == 404, "unknown id is 404")
    check(d.json("GET", "/v1/jobs/../../etc/passwd")[0] == 404, "path tricks are 404")
    check(d.json("GET", "/v1/nothing")[0] == 404, "unknown route is 404")
    check(d.json("GET", "/v1/jobs/1/unknown")[0] == 404, "unknown job resource is 404")
    check(d.json("PUT", "/v1/jobs", {})[0] == 405, "PUT /v1/jobs is 405")
    check(d.json("DELETE", "/v1/info")[0] == 405, "DELETE /v1/info is 405")
    check(d.json("POST", "/healthz", {})[0] == 405, "POST /healthz is 405")
    good = d.submit(SMALL)
    check(d.json("POST", "/v1/jobs/" + good, {})[0] == 405, "POST on a job is 405")
    code, reply = d.json("GET", "/v1/jobs/%s?wait=forever" % good)
    check(code == 400 and reply["error"]["field"] == "wait", "bad wait is 400 naming wait")
    check(d.json("GET", "/v1/jobs/%s?wait=-1" % good)[0] == 400, "negative wait is 400")

    # A full queue answers 429: one job running, 64 waiting.
    long_job = {"frames": 1000000, "warmup_frames": 0, "timeout_s": 0, "scene": {"width": 32, "height": 32}}
    ids = [d.submit(long_job)]
    deadline = time.time() + 30
    while d.json("GET", "/v1/jobs/" + ids[0])[1]["status"] != "running" and time.time() < deadline:
        time.sleep(0.05)
    status = 202
    while status == 202 and len(ids) < 80:
        status, reply = d.json("POST", "/v1/jobs", long_job)
        if status == 202:
            ids.append(reply["id"])
    check(status == 429 and len(ids) == 65, "the 66th job is 429 (%d accepted)" % len(ids))
    check(reply.get("error", {}).get("field") == "body", "429 is a JSON error")
    for i in reversed(ids):
        d.json("DELETE", "/v1/jobs/" + i)

    # Random bodies never crash the daemon.
    rng = random.Random(7)
    alphabet = b'{}[]":,0123456789.-+eEtrufalsn \\x' + bytes(range(0, 256, 17))
    codes = set()
    for _ in range(300):
        n = rng.randint(0, 200)
        body = bytes(rng.choice(alphabet) for _ in range(n))
        codes.add(d.request("POST", "/v1/jobs", body)[0])
    check(codes <= {400, 202}, "random bodies answer 400 (or 202 if valid): %s" % codes)
    for j in d.json("GET", "/v1/jobs")[1]["jobs"]:
        if j["status"] in ("queued", "running"):
            d.json("DELETE", "/v1/jobs/" + j["id"])

    # The daemon still works, and the good job's result was not disturbed.
    check(d.wait(good)["status"] == "done", "the earlier good job finished")
    check(d.run(SMALL)["status"] == "done", "a new job runs after all of that")
    check(d.alive(), "daemon alive")
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_badinput")
