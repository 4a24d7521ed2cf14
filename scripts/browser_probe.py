#!/usr/bin/env python3
"""Opens pages in a real headless Chromium and reports what a test needs to know about them.

Usage: browser_probe.py < REQUEST.json > ANSWER.json

REQUEST: {"pages": [{"url": URL, "ids": [ID, ...], "script": JS (optional)}, ...],
          "screenshot": {"url": URL, "path": PNG, "width": W, "height": H} (optional)}
For each page, in order, in one browser tab: load URL, wait for its load event, run `script`
(if any), then read each element `id`: {"text": its text, "value": its data-value
attribute, "paths": how many SVG paths it holds} (null when absent). ANSWER: {"pages":
[{"url", "elements": {ID: ...}, "requests": [every URL the page asked for], "errors": [uncaught exceptions, console errors and log errors],
"links": [every a[href] resolved], "broken_images": [img src not loaded], "ids": [every id in
the document]}], "browser": the version}.

Chromium is driven over the DevTools protocol on a pipe (--remote-debugging-pipe: file
descriptors 3 and 4, JSON messages ended by NUL), so nothing but the Python standard library is
needed and no port is opened. The browser is the system's: SLIDESTACK_CHROMIUM, else
chromium-headless-shell, chromium or google-chrome on PATH (scripts/install-deps.sh --test
installs Debian's chromium-headless-shell).
"""

import base64
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

TIMEOUT_S = 60.0


def find_browser():
    env = os.environ.get("SLIDESTACK_CHROMIUM")
    if env:
        return env
    for name in ("chromium-headless-shell", "chromium", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    sys.exit(
        "browser_probe.py: no headless Chromium found: run scripts/install-deps.sh --test "
        "(Debian: apt-get install chromium-headless-shell), or set SLIDESTACK_CHROMIUM"
    )


class Browser:
    def __init__(self, path, profile):
        to_chrome_r, to_chrome_w = os.pipe()
        from_chrome_r, from_chrome_w = os.pipe()

        def child_fds():
            # Through fresh descriptors, as either end may already be 3 or 4 (and dup2 onto
            # itself would keep its close-on-exec flag).
            r, w = os.dup(to_chrome_r), os.dup(from_chrome_w)
            os.dup2(r, 3)
            os.dup2(w, 4)

        args = [
            path,
            "--headless",
            "--remote-debugging-pipe",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--no-default-browser-check",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-extensions",
            "--user-data-dir=" + profile,
            "about:blank",
        ]
        self.proc = subprocess.Popen(
            args,
            preexec_fn=child_fds,
            # The browser's pipe is fds 3 and 4, made in `child_fds` after the fork; closing the
            # inherited descriptors would close them.
            close_fds=False,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(to_chrome_r)
        os.close(from_chrome_w)
        self.w = os.fdopen(to_chrome_w, "wb")
        self.r = os.fdopen(from_chrome_r, "rb")
        self.next_id = 0
        self.events = []
        self.buffer = b""
        self.session = None

    def read_message(self):
        while b"\0" not in self.buffer:
            chunk = os.read(self.r.fileno(), 1 << 16)
            if not chunk:
                raise RuntimeError("the browser closed its DevTools pipe")
            self.buffer += chunk
        msg, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(msg)

    def call(self, method, params=None, session=True):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session and self.session:
            msg["sessionId"] = self.session
        self.w.write(json.dumps(msg).encode() + b"\0")
        self.w.flush()
        deadline = time.monotonic() + TIMEOUT_S
        while time.monotonic() < deadline:
            m = self.read_message()
            if m.get("id") == self.next_id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})
            self.events.append(m)
        raise RuntimeError(f"{method}: no answer in {TIMEOUT_S} s")

    def wait_event(self, method):
        deadline = time.monotonic() + TIMEOUT_S
        for i, m in enumerate(self.events):
            if m.get("method") == method:
                del self.events[i]
                return m
        while time.monotonic() < deadline:
            m = self.read_message()
            if m.get("method") == method:
                return m
            self.events.append(m)
        raise RuntimeError(f"no {method} in {TIMEOUT_S} s")

    def close(self):
        try:
            self.call("Browser.close", session=False)
        except Exception:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


COLLECT = """(() => {
  const ids = %s;
  const elements = {};
  for (const id of ids) {
    const e = document.getElementById(id);
    elements[id] = e === null ? null : {text: e.textContent, value: e.getAttribute('data-value'),
                                        paths: e.querySelectorAll('path').length};
  }
  return {
    elements,
    links: Array.from(document.querySelectorAll('a[href]')).map(a => a.href),
    broken_images: Array.from(document.images)
      .filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.src),
    ids: Array.from(document.querySelectorAll('[id]')).map(e => e.id),
  };
})()"""


def drain(browser, page):
    """Moves the events gathered so far into `page`'s requests and errors."""
    for m in browser.events:
        method, p = m.get("method"), m.get("params", {})
        if method == "Network.requestWillBeSent":
            page["requests"].append(p["request"]["url"])
        elif method == "Runtime.exceptionThrown":
            d = p["exceptionDetails"]
            text = d.get("exception", {}).get("description") or d.get("text")
            page["errors"].append(f"exception: {text}")
        elif method == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            args = " ".join(str(a.get("value", a.get("description"))) for a in p.get("args", []))
            page["errors"].append(f"console.{p['type']}: {args}")
        elif method == "Log.entryAdded" and p["entry"].get("level") == "error":
            page["errors"].append(f"log: {p['entry'].get('text')} {p['entry'].get('url', '')}")
        elif method == "Network.loadingFailed":
            page["errors"].append(f"loading failed: {p.get('errorText')}")
    browser.events.clear()


def probe(request):
    profile = tempfile.mkdtemp(prefix="slidestack-chromium-")
    browser = Browser(find_browser(), profile)
    try:
        version = browser.call("Browser.getVersion", session=False).get("product", "")
        target = browser.call("Target.createTarget", {"url": "about:blank"}, session=False)
        attached = browser.call(
            "Target.attachToTarget", {"targetId": target["targetId"], "flatten": True},
            session=False,
        )
        browser.session = attached["sessionId"]
        for domain in ("Page", "Runtime", "Network", "Log"):
            browser.call(domain + ".enable")
        browser.events.clear()
        pages = []
        for spec in request.get("pages", []):
            page = {"url": spec["url"], "requests": [], "errors": []}
            nav = browser.call("Page.navigate", {"url": spec["url"]})
            if nav.get("errorText"):
                page["errors"].append("navigation: " + nav["errorText"])
            else:
                browser.wait_event("Page.loadEventFired")
            if spec.get("script"):
                r = browser.call("Runtime.evaluate", {"expression": spec["script"],
                                                      "awaitPromise": True})
                if "exceptionDetails" in r:
                    page["errors"].append("test script: " + json.dumps(r["exceptionDetails"]))
            r = browser.call("Runtime.evaluate", {
                "expression": COLLECT % json.dumps(spec.get("ids", [])),
                "returnByValue": True,
            })
            page.update(r["result"]["value"])
            # Let late requests and errors arrive before they are counted.
            browser.call("Runtime.evaluate", {
                "expression": "new Promise(r => setTimeout(r, 100))", "awaitPromise": True,
            })
            drain(browser, page)
            pages.append(page)
        shot = request.get("screenshot")
        if shot:
            browser.call("Emulation.setDeviceMetricsOverride", {
                "width": shot["width"], "height": shot["height"], "deviceScaleFactor": 1,
                "mobile": False,
            })
            browser.call("Page.navigate", {"url": shot["url"]})
            browser.wait_event("Page.loadEventFired")
            png = browser.call("Page.captureScreenshot", {"format": "png"})
            with open(shot["path"], "wb") as f:
                f.write(base64.b64decode(png["data"]))
        return {"browser": version, "pages": pages}
    finally:
        browser.close()
        shutil.rmtree(profile, ignore_errors=True)


if __name__ == "__main__":
    json.dump(probe(json.load(sys.stdin)), sys.stdout)
