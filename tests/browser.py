"""A headless Chromium driven over the Chrome DevTools Protocol on a pipe (no extra package,
no network): enough to load a page, evaluate JavaScript, click, watch for dialogs and take a
screenshot. Used by ``tests/views/test_view.py``.

Chromium reads commands from its fd 3 and writes replies to fd 4 when started with
``--remote-debugging-pipe``; each message is one JSON object followed by a NUL byte.
"""

from __future__ import annotations

import base64
import fcntl
import json
import os
import queue
import shutil
import subprocess
import tempfile
import threading
import time

CANDIDATES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable", "chrome")


def find_browser() -> str | None:
    """A Chromium-family executable: $ATLAS_BROWSER, else the first on PATH."""
    explicit = os.environ.get("ATLAS_BROWSER")
    if explicit:
        return explicit if os.access(explicit, os.X_OK) else None
    for name in CANDIDATES:
        path = shutil.which(name)
        if path:
            return path
    return None


class BrowserError(RuntimeError):
    pass


class Browser:
    """One headless browser with one page (a flat CDP session)."""

    def __init__(self, executable: str, width: int = 1220, height: int = 640):
        self.profile = tempfile.mkdtemp(prefix="atlas-chromium-")
        self.log = open(os.path.join(self.profile, "stderr.log"), "wb")  # noqa: SIM115
        to_child_r, self._to_child = os.pipe()
        self._from_child, from_child_w = os.pipe()
        # Move the child's ends above 9, then let bash place them at 3 and 4 for the
        # browser (no preexec_fn: that is unsafe in a process with threads).
        hi_r = fcntl.fcntl(to_child_r, fcntl.F_DUPFD, 10)
        hi_w = fcntl.fcntl(from_child_w, fcntl.F_DUPFD, 10)
        os.close(to_child_r)
        os.close(from_child_w)
        flags = ["--headless", "--remote-debugging-pipe", "--no-sandbox",
                 "--disable-gpu", "--no-first-run", "--no-default-browser-check",
                 "--disable-extensions", "--disable-background-networking",
                 "--disable-dev-shm-usage", "--mute-audio", f"--user-data-dir={self.profile}",
                 "about:blank"]
        script = f'exec "$0" "$@" 3<&{hi_r} 4>&{hi_w}'
        self.proc = subprocess.Popen([shutil.which("bash") or "/bin/bash", "-c", script,
                                      executable, *flags],
                                     stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=self.log, pass_fds=(hi_r, hi_w))
        os.close(hi_r)
        os.close(hi_w)
        self._next = 0
        self._closed = False
        self._replies: dict[int, queue.Queue] = {}
        self._lock = threading.Lock()
        self.events: list[tuple[str, dict]] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        self.session = None
        try:
            target = self.send("Target.createTarget", {"url": "about:blank"})["targetId"]
            self.session = self.send("Target.attachToTarget",
                                     {"targetId": target, "flatten": True})["sessionId"]
            for domain in ("Page.enable", "Runtime.enable"):
                self.call(domain)
            self.call("Emulation.setDeviceMetricsOverride",
                      {"width": width, "height": height, "deviceScaleFactor": 1,
                       "mobile": False})
        except BaseException:
            self.close()
            raise

    def _read(self):
        buffer = b""
        while True:
            try:
                chunk = os.read(self._from_child, 1 << 16)
            except OSError:
                chunk = b""
            if not chunk:
                break
            buffer += chunk
            while b"\0" in buffer:
                raw, buffer = buffer.split(b"\0", 1)
                message = json.loads(raw)
                if "id" in message:
                    with self._lock:
                        box = self._replies.get(message["id"])
                    if box is not None:
                        box.put(message)
                else:
                    self.events.append((message.get("method"), message.get("params", {})))
                    if message.get("method") == "Page.javascriptDialogOpening":
                        # answer it, or the page would hang; the test sees the event
                        self._post("Page.handleJavaScriptDialog", {"accept": True},
                                   message.get("sessionId"))
        with self._lock:
            self._closed = True
            for box in self._replies.values():
                box.put({"error": {"message": "the browser closed the pipe"}})

    def _post(self, method, params=None, session=None) -> int:
        with self._lock:
            if self._closed:
                raise BrowserError(f"{method}: the browser is gone ({self._log_tail()})")
            self._next += 1
            ident = self._next
            self._replies[ident] = queue.Queue()
        message = {"id": ident, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        try:
            os.write(self._to_child, json.dumps(message).encode() + b"\0")
        except OSError as exc:
            raise BrowserError(f"{method}: the browser is gone ({exc}; "
                               f"{self._log_tail()})") from None
        return ident

    def send(self, method, params=None, session=None, timeout=30.0) -> dict:
        ident = self._post(method, params, session)
        try:
            reply = self._replies[ident].get(timeout=timeout)
        except queue.Empty:
            raise BrowserError(f"{method}: no reply within {timeout} s") from None
        finally:
            with self._lock:
                self._replies.pop(ident, None)
        if "error" in reply:
            raise BrowserError(f"{method}: {reply['error'].get('message')}")
        return reply.get("result", {})

    def _log_tail(self) -> str:
        try:
            with open(self.log.name, "rb") as f:
                lines = f.read().decode(errors="replace").strip().splitlines()
        except OSError:
            return "no log"
        return lines[-1] if lines else "its log is empty"

    def call(self, method, params=None, timeout=30.0) -> dict:
        """A command to the page's session."""
        return self.send(method, params, self.session, timeout)

    def goto(self, url: str, timeout=30.0) -> None:
        self.events.clear()
        self.call("Page.navigate", {"url": url})
        deadline = time.monotonic() + timeout
        while not any(m == "Page.loadEventFired" for m, _ in self.events):
            if time.monotonic() > deadline:
                raise BrowserError(f"{url}: not loaded within {timeout} s")
            time.sleep(0.02)

    def evaluate(self, expression: str, timeout=30.0):
        """The JSON value of a JavaScript expression (promises awaited)."""
        result = self.call("Runtime.evaluate", {"expression": expression, "awaitPromise": True,
                                                "returnByValue": True}, timeout)
        if "exceptionDetails" in result:
            details = result["exceptionDetails"]
            text = details.get("exception", {}).get("description") or details.get("text")
            raise BrowserError(f"JavaScript error: {text}")
        return result["result"].get("value")

    def click(self, x: float, y: float) -> None:
        for kind in ("mousePressed", "mouseReleased"):
            self.call("Input.dispatchMouseEvent", {"type": kind, "x": x, "y": y,
                                                   "button": "left", "clickCount": 1})

    def screenshot(self, clip: dict | None = None) -> bytes:
        params = {"format": "png"}
        if clip:
            params["clip"] = {**clip, "scale": 1}
        return base64.b64decode(self.call("Page.captureScreenshot", params)["data"])

    def dialogs(self) -> list[dict]:
        return [p for m, p in self.events if m == "Page.javascriptDialogOpening"]

    def console_errors(self) -> list[str]:
        out = []
        for method, params in self.events:
            if method == "Runtime.exceptionThrown":
                details = params.get("exceptionDetails", {})
                out.append(details.get("exception", {}).get("description")
                           or details.get("text", "?"))
            elif method == "Runtime.consoleAPICalled" and params.get("type") == "error":
                out.append(" ".join(str(a.get("value", a.get("description", "")))
                                    for a in params.get("args", [])))
        return out

    def close(self) -> None:
        try:
            self.send("Browser.close", timeout=5)
        except BrowserError:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        for fd in (self._to_child, self._from_child):
            try:
                os.close(fd)
            except OSError:
                pass
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)
