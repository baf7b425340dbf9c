"""Open an HTML page in headless Chromium and check it: every image decoded, every video's metadata loaded,
no console error, no uncaught exception, no failed request (each distinct problem listed once). Optionally save a
screenshot.

    PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.html_check PAGE.html [--screenshot OUT.png]
        [--width 1280] [--height 2000]

Talks to Chromium over the DevTools protocol on a pipe (--remote-debugging-pipe: JSON messages, each ended by
a NUL byte, written to its fd 3 and read from its fd 4), Python's standard library only. Exit status: 0 the page
is clean, 1 problems (listed), 77 Chromium cannot start here (the reason is printed).
"""
import argparse
import base64
import json
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync", "--mute-audio",
         "--autoplay-policy=no-user-gesture-required", "--allow-file-access-from-files"]

# every image complete with a width, every video with metadata (readyState >= 1) or an error, within 30 s
CHECK = """
new Promise(resolve => {
  const t0 = Date.now();
  function poll() {
    const imgs = [...document.images].map(i => ({src: i.src.slice(0, 80), ok: i.complete && i.naturalWidth > 0}));
    const vids = [...document.querySelectorAll('video')].map(v => ({src: v.currentSrc || v.src,
        ok: v.readyState >= 1 && !v.error, err: v.error ? v.error.code : 0, duration: v.duration,
        width: v.videoWidth}));
    const pending = vids.some(v => !v.ok && !v.err) || imgs.some(i => !i.ok);
    if (pending && Date.now() - t0 < 30000) { setTimeout(poll, 200); return; }
    resolve(JSON.stringify({imgs, vids, title: document.title, h2: document.querySelectorAll('h2').length,
                            height: document.documentElement.scrollHeight}));
  }
  poll();
})
"""


class Cdp:
    def __init__(self, proc, w, r):
        self.proc, self.w, self.r = proc, w, r
        self.buf = b""
        self.next_id = 0
        self.events = []

    def send(self, method, params=None, session=None, timeout=60):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self.w, json.dumps(msg).encode() + b"\0")
        want = self.next_id
        end = time.time() + timeout
        while time.time() < end:
            for m in self.read(end - time.time()):
                if m.get("id") == want:
                    if "error" in m:
                        raise RuntimeError(f"{method}: {m['error']}")
                    return m.get("result", {})
                self.events.append(m)
        raise TimeoutError(f"no answer to {method} within {timeout} s")

    def read(self, timeout):
        ready, _, _ = select.select([self.r], [], [], max(timeout, 0))
        if not ready:
            return []
        chunk = os.read(self.r, 1 << 20)
        if not chunk:
            raise RuntimeError("Chromium closed the DevTools pipe")
        self.buf += chunk
        out = []
        while b"\0" in self.buf:
            raw, self.buf = self.buf.split(b"\0", 1)
            out.append(json.loads(raw))
        return out

    def wait_event(self, method, timeout):
        end = time.time() + timeout
        while time.time() < end:
            for i, m in enumerate(self.events):
                if m.get("method") == method:
                    return self.events.pop(i)
            self.events += self.read(min(0.5, end - time.time()))
        raise TimeoutError(f"no {method} within {timeout} s")


def chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        p = shutil.which(name) or (f"/usr/bin/{name}" if os.path.exists(f"/usr/bin/{name}") else None)
        if p:
            return p
    return None


class CannotStart(Exception):
    pass


def check(page, screenshot=None, width=1280, height=2000):
    """(problems, facts): problems is a list of strings (empty: clean); facts what the page held"""
    exe = chromium()
    if exe is None:
        raise CannotStart("no chromium on this machine (apt-get install chromium)")
    profile = tempfile.mkdtemp(prefix="divcoll-chromium-")
    to_r, to_w = os.pipe()    # we write, Chromium reads on fd 3
    from_r, from_w = os.pipe()  # Chromium writes on fd 4, we read

    def child_fds():
        os.dup2(to_r, 3)
        os.dup2(from_w, 4)

    args = [exe, *FLAGS, f"--user-data-dir={profile}", "--remote-debugging-pipe", f"--window-size={width},{height}",
            "about:blank"]
    # Chromium's stderr goes to a file, not a pipe nobody drains (a full pipe would stall it)
    err_path = os.path.join(profile, "stderr.txt")
    try:
        with open(err_path, "wb") as err_file:
            proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=err_file,
                                    pass_fds=(3, 4), preexec_fn=child_fds)
    except OSError as e:
        shutil.rmtree(profile, ignore_errors=True)
        raise CannotStart(f"cannot start {exe}: {e}")
    os.close(to_r)
    os.close(from_w)
    cdp = Cdp(proc, to_w, from_r)
    problems, facts = [], {}
    try:
        try:
            target = cdp.send("Target.createTarget", {"url": "about:blank"}, timeout=60)["targetId"]
        except (RuntimeError, TimeoutError) as e:
            with open(err_path, "rb") as fh:
                err = fh.read(4000).decode(errors="replace") if proc.poll() is not None else ""
            raise CannotStart(f"{exe} did not answer on the DevTools pipe ({e}) {err.strip()[:300]}")
        session = cdp.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for dom in ("Runtime", "Log", "Page", "Network"):
            cdp.send(f"{dom}.enable", session=session)
        cdp.send("Emulation.setDeviceMetricsOverride", {"width": width, "height": height, "deviceScaleFactor": 1,
                                                         "mobile": False}, session=session)
        url = "file://" + os.path.abspath(page)
        cdp.send("Page.navigate", {"url": url}, session=session)
        cdp.wait_event("Page.loadEventFired", 120)
        res = cdp.send("Runtime.evaluate", {"expression": CHECK, "awaitPromise": True, "returnByValue": True},
                       session=session, timeout=60)
        facts = json.loads(res["result"]["value"])
        for i in facts["imgs"]:
            if not i["ok"]:
                problems.append(f"image did not load: {i['src']}")
        for v in facts["vids"]:
            if not v["ok"]:
                problems.append(f"video did not load (MediaError {v['err']}): {v['src']}")
        if screenshot:
            shot = cdp.send("Page.captureScreenshot", {"format": "png"}, session=session)
            with open(screenshot, "wb") as fh:
                fh.write(base64.b64decode(shot["data"]))
        # the navigation can move the page to a new renderer process, whose first console messages and log entries
        # can come before the session's domains take hold there (on a loaded machine); Chromium replays the ones it
        # kept when a domain is enabled again, and the duplicates this makes are dropped below
        for dom in ("Runtime", "Log"):
            cdp.send(f"{dom}.disable", session=session)
            cdp.send(f"{dom}.enable", session=session)
        # the page's console and network events: read until the pipe has been quiet for 0.5 s (at most 10 s), not
        # one read, so that events still in flight on a loaded machine are not missed
        end = time.time() + 10
        while time.time() < end:
            got = cdp.read(0.5)
            cdp.events += got
            if not got and not cdp.buf:
                break
        for m in cdp.events:
            meth, p = m.get("method"), m.get("params", {})
            if meth == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                problems.append("console error: " + " ".join(str(a.get("value", a.get("description", "")))
                                                             for a in p.get("args", [])))
            elif meth == "Runtime.exceptionThrown":
                problems.append("uncaught exception: " + p.get("exceptionDetails", {}).get("text", ""))
            elif meth == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
                e = p["entry"]
                problems.append(f"console error ({e.get('source')}): {e.get('text')} {e.get('url', '')}")
            elif meth == "Network.loadingFailed" and not p.get("canceled"):
                problems.append(f"request failed: {p.get('errorText')}")
        problems = list(dict.fromkeys(problems))  # each distinct problem once, in the order first seen
        try:
            cdp.send("Browser.close", timeout=10)
        except (RuntimeError, TimeoutError):
            pass
    finally:
        try:
            proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        os.close(to_w)
        os.close(from_r)
        shutil.rmtree(profile, ignore_errors=True)
    return problems, facts


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("page", help="HTML file")
    ap.add_argument("--screenshot", help="PNG of the page's first screen")
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=2000)
    a = ap.parse_args(argv)
    try:
        problems, facts = check(a.page, a.screenshot, a.width, a.height)
    except CannotStart as e:
        print(f"html_check: skipped: {e}")
        return 77
    print(f"html_check: {a.page}: {len(facts.get('imgs', []))} images, {len(facts.get('vids', []))} videos, "
          f"{facts.get('h2', 0)} sections")
    for p in problems:
        print(f"html_check: {p}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
