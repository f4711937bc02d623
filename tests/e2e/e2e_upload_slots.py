#!/usr/bin/env python3
"""Upload slots a slow client cannot hold (issue 34, item 4): four chunked
PUTs sending a byte every 2 s from one address (before: they held all four
upload slots for about 290 s, and every other client got 429). Now:

- an address holds at most 2 of the 4 slots: the third and fourth slow
  uploads get 429 with a Retry-After;
- a fifth upload, from another address (127.0.0.2, still loopback), gets
  in at once;
- a slow body is cut once it has brought less than the minimum rate over
  a window (32 KiB/s over 10 s), which frees its slot: an upload from the
  slow address, retried after its Retry-After, gets in.

The uploads' success needs the real converter beside the daemon."""

import http.client
import json
import os
import socket
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import testlib  # noqa: E402
from testlib import Daemon, check, stop_and_check  # noqa: E402
from e2e_assets import converter_path, glb  # noqa: E402

S = testlib.TIME_SCALE


class SlowUpload:
    """A chunked PUT that sends one byte every period seconds until the
    daemon answers or closes the connection."""

    def __init__(self, port, name, period=2.0):
        self.sock = socket.create_connection(("127.0.0.1", port))
        self.sock.sendall(("PUT /v1/assets/%s HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                           "Content-Type: application/octet-stream\r\n"
                           "Transfer-Encoding: chunked\r\n\r\n" % name).encode())
        self.period = period
        self.answer = b""
        self.closed_at = None
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self):
        self.sock.settimeout(self.period)
        t0 = time.time()
        while not self.stop.is_set():
            try:
                data = self.sock.recv(65536)
                if not data:
                    break
                self.answer += data
                if b"\r\n\r\n" in self.answer:
                    break
            except socket.timeout:
                try:
                    self.sock.sendall(b"1\r\nA\r\n")
                except OSError:
                    break
            except OSError:
                break
        self.closed_at = time.time() - t0

    def status(self):
        line = self.answer.split(b"\r\n", 1)[0].split()
        return int(line[1]) if len(line) > 1 else None

    def header(self, name):
        for line in self.answer.split(b"\r\n\r\n", 1)[0].split(b"\r\n")[1:]:
            k, _, v = line.partition(b":")
            if k.strip().lower() == name.lower().encode():
                return v.strip().decode()
        return None

    def close(self):
        self.stop.set()
        self.sock.close()


def put_from(port, source, name, data):
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=120 * S,
                                      source_address=(source, 0))
    try:
        conn.request("PUT", "/v1/assets/" + name, body=data,
                     headers={"Content-Type": "application/octet-stream"})
        resp = conn.getresponse()
        body = resp.read()
        try:
            body = json.loads(body)
        except ValueError:
            pass
        return resp.status, dict(resp.getheaders()), body
    finally:
        conn.close()


def main():
    if not os.access(converter_path(), os.X_OK):
        print("SKIP: no converter at %s" % converter_path())
        sys.exit(77)
    # A 3 s rate window, not 10 (SHADEBENCH_DEBUG_UPLOAD_WINDOW_S): the slow
    # uploads are cut 3 s after their headers. Everything that needs them
    # holding their slots (the 429s, the fifth upload let in beside them)
    # is done in the first few tenths of a second, under the sanitizers too
    # (0.2 s there at load 3), so the window does not stretch with S.
    d = Daemon(env={"SHADEBENCH_DEBUG_UPLOAD_WINDOW_S": "3"})
    slow = []
    try:
        code, info = d.json("GET", "/v1/info")
        assets = info.get("limits", {}).get("assets", {})
        check(assets.get("max_uploads_per_address") == 2 and
              assets.get("upload_min_bytes_per_s", 0) > 0,
              "/v1/info states the uploads' share and rate (%s)" % assets)
        window = assets.get("upload_rate_window_s", 10)

        check(window == 3, "the test's shorter rate window is in force (%s s)" % window)

        slow = [SlowUpload(d.port, "slow%d.glb" % i) for i in range(4)]
        # Two answers come at once; the other two never do (their bodies go on).
        deadline = time.time() + 10 * S
        while sum(u.status() == 429 for u in slow) < 2 and time.time() < deadline:
            time.sleep(0.02)
        time.sleep(0.1)
        refused = [u for u in slow if u.status() == 429]
        holding = [u for u in slow if u not in refused]
        check(len(refused) == 2, "two of four slow uploads from one address get 429 (%s)"
              % [u.status() for u in slow])
        for u in refused:
            after = u.header("Retry-After")
            check(after is not None and 1 <= int(after) <= window + 1,
                  "a 429 says when to retry (Retry-After: %s)" % after)

        code, headers, body = put_from(d.port, "127.0.0.1", "sixth.glb", glb(3.0))
        check(code == 429 and "Retry-After" in headers,
              "another from the slow address waits its turn (%d %s)" % (code, headers))

        alive = [u.thread.is_alive() for u in holding]
        t0 = time.time()
        code, _, body = put_from(d.port, "127.0.0.2", "fifth.glb", glb(2.0))
        check(code == 201 and alive == [True, True],
              "a fifth upload, from another address, gets in at once while the two slow ones "
              "hold their slots (%d %s, %.1f s; holding: %s)"
              % (code, body, time.time() - t0, alive))

        # The slow ones are cut within a window or two of their headers.
        deadline = time.time() + (3 * window + 10) * S
        while any(u.thread.is_alive() for u in holding) and time.time() < deadline:
            time.sleep(0.2)
        cut = [u for u in holding if not u.thread.is_alive()]
        check(len(cut) == 2, "the two slow uploads holding slots are cut (closed after %s s)"
              % [round(u.closed_at or -1, 1) for u in holding])
        metrics = d.request("GET", "/metrics")[2].decode()
        check("shadebench_http_uploads_slow_total 2" in metrics,
              "/metrics counts the slow uploads cut")
        code, _, body = put_from(d.port, "127.0.0.1", "sixth.glb", glb(3.0))
        check(code == 201, "then the slow address's next upload gets in (%d %s)" % (code, body))
        code, _ = d.json("GET", "/healthz")
        check(code == 200, "healthy")
    finally:
        for u in slow:
            u.close()
        stop_and_check(d)
    testlib.finish("e2e_upload_slots")


if __name__ == "__main__":
    main()
