"""Headless Chromium driven over the DevTools protocol, for the viewer's browser tests.

:class:`Browser` starts Chromium with the DevTools protocol on a pipe (no extra dependency), its
network routed to a dead proxy; :class:`Page` is one tab: load, wait for a JavaScript condition,
evaluate, seek the meshcat animation, screenshot, and the console messages, uncaught exceptions,
browser log entries and network requests it recorded. ``PKDYN_CHROMIUM`` names the browser
(default ``/usr/bin/chromium``); ``PKDYN_VIEWER_SHOTS`` a directory to keep the screenshots in.
"""

from __future__ import annotations

import base64
import io
import json
import os
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
from PIL import Image

__all__ = ["CHROMIUM", "H", "W", "Browser", "Page"]

CHROMIUM = os.environ.get("PKDYN_CHROMIUM", "/usr/bin/chromium")
W, H = 800, 600
"""Window size of the tabs [px]."""


class Browser:
    """Headless Chromium driven over the DevTools protocol on a pipe (no extra dependency).

    Pages are checked through the protocol rather than ``--screenshot``/``--virtual-time-budget``
    (which hangs now and then on a loaded machine): load, wait for a JavaScript condition, pause
    and seek the animation, screenshot; console calls, uncaught exceptions, browser log entries
    (failed loads) and network requests are recorded per page.
    """

    def __init__(self, workdir: Path) -> None:
        cmd_r, self._cmd_w = os.pipe()  # we write commands, Chromium reads them on fd 3
        self._evt_r, evt_w = os.pipe()  # Chromium writes replies and events on fd 4

        def fds() -> None:
            os.dup2(cmd_r, 3)
            os.dup2(evt_w, 4)

        self.proc = subprocess.Popen(
            [
                CHROMIUM,
                "--headless=new",
                "--no-sandbox",
                "--use-angle=swiftshader",  # WebGL in software
                "--enable-unsafe-swiftshader",
                "--hide-scrollbars",
                "--remote-debugging-pipe",
                f"--user-data-dir={workdir / 'profile'}",
                "--proxy-server=127.0.0.1:9",  # any request off this machine fails
                "--disable-background-networking",
                "--disable-component-update",
                "--no-first-run",
                f"--window-size={W},{H}",
            ],
            pass_fds=(3, 4),
            preexec_fn=fds,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(cmd_r)
        os.close(evt_w)
        self._id = 0
        self._replies: dict[int, dict] = {}
        self.events: list[dict] = []
        self._cv = threading.Condition()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        buf = b""
        while chunk := os.read(self._evt_r, 1 << 16):
            *messages, buf = (buf + chunk).split(b"\0")
            with self._cv:
                for m in messages:
                    d = json.loads(m)
                    if "id" in d:
                        self._replies[d["id"]] = d
                    else:
                        self.events.append(d)
                self._cv.notify_all()

    def call(self, method: str, params: dict | None = None, session: str | None = None) -> dict:
        self._id += 1
        key = self._id
        msg: dict = {"id": key, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self._cmd_w, json.dumps(msg).encode() + b"\0")
        with self._cv:
            assert self._cv.wait_for(lambda: key in self._replies, 60), f"{method}: no reply"
            reply = self._replies.pop(key)
        assert "error" not in reply, f"{method}: {reply['error']}"
        return reply["result"]

    def open(self, target: str, ready: str = "document.body.hasAttribute('data-pkdyn-commands')"):
        """A new tab on ``target`` (file path or URL), once ``ready`` (JavaScript) is true."""
        return Page(self, target if "://" in target else Path(target).resolve().as_uri(), ready)

    def close(self) -> None:
        try:
            self.call("Browser.close")
            self.proc.wait(timeout=20)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()


class Page:
    """One browser tab (see :class:`Browser`)."""

    def __init__(self, browser: Browser, url: str, ready: str) -> None:
        self.browser = browser
        target = browser.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        self.session = browser.call("Target.attachToTarget", {"targetId": target, "flatten": True})[
            "sessionId"
        ]
        for domain in ("Page", "Runtime", "Network", "Log"):
            self.call(f"{domain}.enable")
        metrics = {"width": W, "height": H, "deviceScaleFactor": 1, "mobile": False}
        self.call("Emulation.setDeviceMetricsOverride", metrics)
        self.call("Page.navigate", {"url": url})
        for _ in range(600):
            if self.eval(
                f"(() => {{ try {{ return !!({ready}); }} catch (e) {{ return false; }} }})()"
            ):
                break
            time.sleep(0.05)
        else:
            raise AssertionError(f"{url}: never ready ({ready}); log: {self.problems()}")

    def call(self, method: str, params: dict | None = None) -> dict:
        return self.browser.call(method, params, self.session)

    def eval(self, expression: str, wait: bool = False):
        """Evaluate JavaScript in the page (``wait``: await the promise it returns)."""
        r = self.call(
            "Runtime.evaluate",
            {"expression": expression, "awaitPromise": wait, "returnByValue": True},
        )
        assert "exceptionDetails" not in r, r["exceptionDetails"]
        return r["result"].get("value")

    def seek(self, t: float) -> None:
        """Stop the animation at ``t`` [s]."""
        self.eval(f"viewer.animator.pause(); viewer.animator.seek({t}); viewer.set_dirty()")

    def shot(self, name: str) -> np.ndarray:
        """Screenshot (H, W, 3) of the tab, brought to the front, after two rendered frames.

        Saved as ``<name>.png`` in ``$PKDYN_VIEWER_SHOTS`` when that is set (to look at them).
        """
        self.call("Page.bringToFront")  # background tabs get no animation frames
        self.eval(
            "new Promise(r => { requestAnimationFrame(() => requestAnimationFrame(r));"
            " setTimeout(r, 3000); })",
            True,
        )
        data = self.call("Page.captureScreenshot", {"format": "png"})["data"]
        png = base64.b64decode(data)
        if os.environ.get("PKDYN_VIEWER_SHOTS"):
            (Path(os.environ["PKDYN_VIEWER_SHOTS"]) / f"{name}.png").write_bytes(png)
        image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), int)
        assert image.shape == (H, W, 3)
        return image

    def _events(self, *methods: str) -> list[dict]:
        return [
            e
            for e in self.browser.events
            if e.get("sessionId") == self.session and e["method"] in methods
        ]

    def problems(self) -> list[str]:
        """Console calls, uncaught exceptions and browser log entries (failed loads...)."""
        out = []
        for e in self._events("Runtime.consoleAPICalled"):
            out.append(f"console.{e['params']['type']}: {e['params']['args']}")
        for e in self._events("Runtime.exceptionThrown"):
            out.append(f"uncaught: {e['params']['exceptionDetails']}")
        for e in self._events("Log.entryAdded"):
            out.append(f"log {e['params']['entry']['level']}: {e['params']['entry']['text']}")
        return out

    def requests(self) -> list[str]:
        """URLs the page asked for over the network (not file: or data:)."""
        urls = [e["params"]["request"]["url"] for e in self._events("Network.requestWillBeSent")]
        return [u for u in urls if not u.startswith(("file:", "data:"))]
