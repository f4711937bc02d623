"""Headless Chromium driven over the DevTools protocol on a pipe
(--remote-debugging-pipe), with the standard library only: no WebDriver,
no websocket. One page: navigate, evaluate JavaScript (promises awaited),
real mouse and key input, screenshots, and every console message,
uncaught exception and browser log entry recorded (console_errors)."""

import base64
import json
import os
import shutil
import subprocess
import tempfile
import threading
import time

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


class BrowserError(RuntimeError):
    pass


class Browser:
    def __init__(self, width=1400, height=1000, time_scale=1.0):
        if not CHROMIUM:
            raise BrowserError("chromium is not installed (tools/setup installs it)")
        self.time_scale = time_scale
        self.profile = tempfile.mkdtemp(prefix="shadebench-chromium-")
        cmd_r, self._cmd_w = os.pipe()   # Chromium reads commands on its fd 3
        self._res_r, res_w = os.pipe()   # and writes answers on its fd 4

        def fds():
            # Out of the way first: the pipes may be fds 3 and 4 already.
            a, b = os.dup(cmd_r), os.dup(res_w)
            os.dup2(a, 3)  # dup2 makes them inheritable
            os.dup2(b, 4)
        # The flags keep headless Chromium off the network and the GPU.
        self.proc = subprocess.Popen(
            [CHROMIUM, "--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic",
             "--no-first-run", "--disable-background-networking", "--disable-component-update",
             "--disable-sync", "--disable-extensions", "--disable-dev-shm-usage",
             "--remote-debugging-pipe", "--user-data-dir=" + self.profile, "about:blank"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            preexec_fn=fds, close_fds=False)
        os.close(cmd_r)
        os.close(res_w)
        self._next = 0
        self._answers = {}
        self._cv = threading.Condition()
        self.events = []
        self.console = []       # every console message, exception and log entry
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        self.session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Page", "Runtime", "Log"):
            self.send(domain + ".enable")
        self.send("Emulation.setDeviceMetricsOverride",
                  {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False})

    def _read(self):
        buf = b""
        while True:
            try:
                chunk = os.read(self._res_r, 1 << 16)
            except OSError:
                chunk = b""
            if not chunk:
                with self._cv:
                    self._answers[None] = True
                    self._cv.notify_all()
                return
            buf += chunk
            while b"\0" in buf:
                raw, buf = buf.split(b"\0", 1)
                msg = json.loads(raw)
                with self._cv:
                    if "id" in msg:
                        self._answers[msg["id"]] = msg
                    else:
                        self._event(msg)
                    self._cv.notify_all()

    def _event(self, msg):
        method, p = msg.get("method"), msg.get("params", {})
        self.events.append(msg)
        if method == "Runtime.consoleAPICalled":
            text = " ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", []))
            frames = p.get("stackTrace", {}).get("callFrames", [])
            where = " (at %s)" % ", ".join("%s %s:%d" % (f.get("functionName") or "?", f.get("url", "").rsplit("/", 1)[-1],
                                                     f.get("lineNumber", 0) + 1) for f in frames[:4]) if frames else ""
            self.console.append("console.%s: %s%s" % (p.get("type"), text, where))
        elif method == "Runtime.exceptionThrown":
            d = p.get("exceptionDetails", {})
            self.console.append("exception: %s %s" % (d.get("text"), d.get("exception", {}).get("description", "")))
        elif method == "Log.entryAdded":
            e = p.get("entry", {})
            self.console.append("log.%s: %s %s" % (e.get("level"), e.get("text"), e.get("url", "")))

    def call(self, method, params=None, session=None, timeout=60):
        with self._cv:
            self._next += 1
            mid = self._next
        msg = {"id": mid, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self._cmd_w, json.dumps(msg).encode() + b"\0")
        deadline = time.time() + timeout * self.time_scale
        with self._cv:
            while mid not in self._answers:
                if None in self._answers:
                    raise BrowserError("chromium exited")
                left = deadline - time.time()
                if left <= 0:
                    raise BrowserError("no answer to %s" % method)
                self._cv.wait(left)
            answer = self._answers.pop(mid)
        if "error" in answer:
            raise BrowserError("%s: %s" % (method, answer["error"]))
        return answer.get("result", {})

    def send(self, method, params=None, timeout=60):
        return self.call(method, params, session=self.session, timeout=timeout)

    def goto(self, url):
        self.send("Page.navigate", {"url": url})

    def eval(self, expression, timeout=60):
        """The value of a JavaScript expression (a promise is awaited)."""
        r = self.send("Runtime.evaluate", {"expression": expression, "returnByValue": True,
                                           "awaitPromise": True}, timeout=timeout)
        if "exceptionDetails" in r:
            raise BrowserError("%s: %s" % (expression[:80], r["exceptionDetails"].get("exception", {}).get(
                "description", r["exceptionDetails"].get("text"))))
        return r.get("result", {}).get("value")

    def wait(self, expression, timeout=60, what=None):
        """Polls until the expression is truthy; its value."""
        deadline = time.time() + timeout * self.time_scale
        last = None
        while time.time() < deadline:
            try:
                last = self.eval(expression)
            except BrowserError as e:
                last = e
            # JavaScript's truth: an element (serialised as {}) counts.
            if not isinstance(last, BrowserError) and last not in (None, False, 0, ""):
                return True if last == {} else last
            time.sleep(0.1)
        raise BrowserError("timed out waiting for %s (last: %s)" % (what or expression, last))

    def click(self, x, y):
        for kind in ("mousePressed", "mouseReleased"):
            self.send("Input.dispatchMouseEvent", {"type": kind, "x": x, "y": y, "button": "left",
                                                   "buttons": 1 if kind == "mousePressed" else 0,
                                                   "clickCount": 1})

    def move(self, x, y):
        self.send("Input.dispatchMouseEvent", {"type": "mouseMoved", "x": x, "y": y})

    def key(self, key, code, keycode):
        for kind in ("keyDown", "keyUp"):
            self.send("Input.dispatchKeyEvent", {"type": kind, "key": key, "code": code,
                                                 "windowsVirtualKeyCode": keycode,
                                                 "text": key if kind == "keyDown" else ""})

    def type_text(self, text):
        self.send("Input.insertText", {"text": text})

    def center(self, selector):
        """The middle of an element on screen, after scrolling it into view."""
        return self.eval("(() => { const e = document.querySelector(%s); e.scrollIntoView({block: 'center'});"
                         " const r = e.getBoundingClientRect(); return [r.x + r.width / 2, r.y + r.height / 2,"
                         " r.x, r.y, r.width, r.height]; })()" % json.dumps(selector))

    def screenshot(self, path, full=True):
        params = {"format": "png"}
        if full:
            h = self.eval("Math.ceil(document.documentElement.scrollHeight)")
            w = self.eval("Math.ceil(document.documentElement.scrollWidth)")
            params.update({"captureBeyondViewport": True,
                           "clip": {"x": 0, "y": 0, "width": w, "height": min(h, 6000), "scale": 1}})
        data = self.send("Page.captureScreenshot", params, timeout=120)["data"]
        with open(path, "wb") as f:
            f.write(base64.b64decode(data))

    def close(self):
        try:
            self.call("Browser.close", timeout=10)
        except BrowserError:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        os.close(self._cmd_w)
        shutil.rmtree(self.profile, ignore_errors=True)
