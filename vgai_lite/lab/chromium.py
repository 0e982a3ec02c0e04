"""Headless Chromium driven through its DevTools protocol over a websocket (websocket-client, a
dependency of Jupyter's; no driver): a free port, waiting for a server, the browser, the client.

Used by ``python -m vgai_lite pdf`` (the book printed page by page, ``vgai_lite.lab.pdf``) and by the
browser tests (tests/test_browser.py, tests/test_site.py)."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import time
import urllib.request

CHROMIUM = next((p for p in (shutil.which("chromium"), shutil.which("chromium-browser"),
                             shutil.which("google-chrome")) if p), None)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_http(url: str, seconds: float, proc: subprocess.Popen, what: str) -> bytes:
    end = time.time() + seconds
    while time.time() < end:
        if proc.poll() is not None:
            raise RuntimeError(f"{what} exited with status {proc.returncode} before it answered at {url}")
        try:
            with urllib.request.urlopen(url, timeout=2) as r:
                return r.read()
        except OSError:
            time.sleep(0.3)
    raise TimeoutError(f"{what} did not answer at {url} within {seconds} s")


def start_chromium(port: int, profile) -> subprocess.Popen:
    """Headless Chromium with its DevTools endpoint on ``port`` and a fresh profile folder, in a process
    group of its own, so that ``stop`` ends its renderer and helper processes too (they write to the
    profile folder: one left running fails the removal of that folder)."""
    return subprocess.Popen([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                             "--no-first-run", "--disable-background-networking", "--disable-component-update",
                             "--disable-sync", "--enable-unsafe-swiftshader", "--window-size=1400,1000",
                             f"--remote-debugging-port={port}", f"--user-data-dir={profile}", "about:blank"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)


class DevTools:
    """The smallest client of Chromium's DevTools protocol: commands on one page, over a websocket.
    Events that arrive while waiting for a command's answer are kept in ``events``."""

    def __init__(self, ws_url: str):
        import websocket  # websocket-client, a dependency of Jupyter's

        self.ws = websocket.create_connection(ws_url, timeout=30, suppress_origin=True)
        self.next_id = 0
        self.events: list = []

    def call(self, method: str, **params):
        self.next_id += 1
        self.ws.send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == self.next_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            if "method" in msg:
                self.events.append(msg)

    def js(self, expression: str):
        res = self.call("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in res:
            raise RuntimeError(f"page script failed: {res['exceptionDetails']}")
        return res["result"].get("value")

    def errors(self) -> list:
        """Console errors, uncaught exceptions and failed loads seen so far (and forget them)."""
        out = []
        for e in self.events:
            m, p = e["method"], e.get("params", {})
            if m == "Runtime.exceptionThrown":
                out.append(p["exceptionDetails"].get("text", "exception") + " " +
                           str(p["exceptionDetails"].get("exception", {}).get("description", ""))[:200])
            elif m == "Runtime.consoleAPICalled" and p.get("type") == "error":
                out.append("console.error: " + " ".join(str(a.get("value", a.get("description", ""))) for a in p["args"]))
            elif m == "Log.entryAdded" and p["entry"].get("level") == "error":
                out.append(f"{p['entry'].get('source')}: {p['entry'].get('text')} {p['entry'].get('url', '')}")
        self.events = []
        return out

    def close(self):
        self.ws.close()


def stop(*procs: subprocess.Popen, seconds: float = 20) -> None:
    """End each process (the browser, a server): terminate, then kill if it has not exited within ``seconds``.
    A process that leads its own group (``start_chromium``'s) takes its whole group with it: the group is
    killed once its leader has gone, so that no child of it outlives the call."""
    for p in procs:
        group = _own_group(p)
        p.terminate() if group is None else _signal_group(group, signal.SIGTERM)
        try:
            p.wait(timeout=seconds)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
        if group is not None:
            _signal_group(group, signal.SIGKILL)


def _own_group(p: subprocess.Popen):
    """The process group ``p`` leads, or None (it shares ours, or has already gone)."""
    try:
        return p.pid if os.getpgid(p.pid) == p.pid else None
    except ProcessLookupError:
        return None


def _signal_group(group: int, sig) -> None:
    try:
        os.killpg(group, sig)
    except ProcessLookupError:  # every process of the group has already exited
        pass
