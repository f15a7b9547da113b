#!/usr/bin/env python3
"""The dashboard binary against what another web page, or a client on this machine, can throw at
it: a real `dashboard` on 127.0.0.1, a free port and a DDS domain of its own, each check well
under 20 s, all traffic to 127.0.0.1, every loop bounded.

  dashboard_guard_test.py DASHBOARD_EXE CHECK [MPDRIG_EXE]

CHECK is one of:
  cross_site  a write (POST /api/shadow) without the page's Origin (or Referer) and the page's
              X-Mpdrig-Token is refused with 403 and a JSON reason: another site's text/plain
              POST, a foreign Origin or Referer with the right token (also one that only looks
              like ours), our Origin without the token or with a wrong one, no Origin nor Referer; the page carries a token, and a
              write made as the page makes it passes the guard (it reaches the feed, which answers
              that no shadow listens: 400, not 403).
  cross_site_shadow  (needs MPDRIG_EXE) as it was found: a rig and its shadow run (`mpdrig serve`,
              `mpdrig shadow`); another site's text/plain POST of set wave_speed_mps=400 is
              refused and the shadow's wave speed stays; the same write made as the page makes it
              is taken, and the shadow then reports wave_speed_mps=400.
  slow        50 clients each send a header line every 2 s (a slowloris): a normal request is
              answered within 1 s meanwhile, and the slow ones are cut off (408) within the
              request deadline (5 s) plus 4 s (one 2 s tick of looking, and slack).
  idle        200 connections that send nothing: a normal request is answered within 1 s, and the
              dashboard has closed them within its idle time (5 s) plus 2 s.
  big_body    a POST declaring a 200 MB body is refused with 413 within 1 s of its head, without
              its body being read; the dashboard's memory (VmRSS) grows by less than 16 MB while
              the client pushes 200 MB at it; a chunked body gets 411; a normal request is
              answered afterwards.
"""
import http.client
import json
import os
import re
import select
import socket
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, "support"))
from test_domain import claim_test_domain, claims  # noqa: E402 (tests/support is not a package)

HOST = "127.0.0.1"


class Dashboard:
    """The dashboard binary on 127.0.0.1 and a free port; it stops by itself after 60 s."""

    def __init__(self, exe, domain=None):
        domain = domain or claim_test_domain()
        self.proc = subprocess.Popen([exe, "--host", HOST, "--port", "0", "--domain", str(domain),
                                      "--duration", "60"], stdout=subprocess.PIPE, text=True,
                                     pass_fds=(claims[domain],))
        line = self.proc.stdout.readline()
        match = re.search(r"http://127\.0\.0\.1:(\d+)/", line)
        if not match:
            self.stop()
            raise AssertionError(f"the dashboard did not say where it listens: {line!r}")
        self.port = int(match.group(1))
        self.origin = f"http://{HOST}:{self.port}"
        print(f"dashboard pid {self.proc.pid} on {self.origin}", flush=True)

    def rss_kb(self):
        with open(f"/proc/{self.proc.pid}/status") as status:
            for line in status:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
        raise AssertionError("no VmRSS")

    def request(self, method, path, headers=None, body=None, timeout_s=10.0):
        """One request on a fresh connection: (status, body text, seconds taken)."""
        started = time.monotonic()
        conn = http.client.HTTPConnection(HOST, self.port, timeout=timeout_s)
        try:
            conn.request(method, path, body=body, headers=headers or {})
            reply = conn.getresponse()
            return reply.status, reply.read().decode(), time.monotonic() - started
        finally:
            conn.close()

    def timed_get(self, what, limit_s):
        """A normal browser request; fails if it is not answered within limit_s."""
        try:
            status, _, took = self.request("GET", "/api/health", timeout_s=limit_s)
        except OSError as err:  # socket.timeout included
            raise AssertionError(f"{what}: GET /api/health not answered within {limit_s} s "
                                 f"({err!r})") from None
        print(f"{what}: GET /api/health -> {status} in {took * 1000:.1f} ms", flush=True)
        assert status == 200, f"{what}: GET /api/health -> {status}"
        return took

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


def connect(port):
    sock = socket.create_connection((HOST, port), timeout=5)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


def closed_by_server(sock):
    """True if the server has closed this connection (EOF or reset; a 408 before it is fine)."""
    try:
        readable, _, _ = select.select([sock], [], [], 0)
        if not readable:
            return False
        sock.setblocking(False)
        while True:
            data = sock.recv(65536)
            if not data:
                return True
    except BlockingIOError:
        return False
    except OSError:
        return True


def check_cross_site(dash):
    shadow = "/api/shadow?rig=mystery&action=set&arg=c%3D400"
    page_status, page, _ = dash.request("GET", "/")
    assert page_status == 200
    own, evil = dash.origin, "http://evil.example"
    match = re.search(r'<meta name="mpdrig-token" content="([0-9a-f]{32})">', page)
    token = match.group(1) if match else "0" * 32
    # What another site's page can make the browser send, and near misses of the page's own.
    refused = {
        "another site's text/plain POST (what a form or fetch from any page sends)":
            ({"Origin": evil, "Content-Type": "text/plain"}, "c=400"),
        "a foreign Origin with the right token": ({"Origin": evil, "X-Mpdrig-Token": token}, ""),
        "Origin null (a sandboxed frame) with the right token":
            ({"Origin": "null", "X-Mpdrig-Token": token}, ""),
        "our host on another port": ({"Origin": f"http://{HOST}:{dash.port + 1}",
                                      "X-Mpdrig-Token": token}, ""),
        "our host:port as a user name before another site":
            ({"Origin": f"http://{HOST}:{dash.port}@evil.example", "X-Mpdrig-Token": token}, ""),
        "a site named after our host": ({"Origin": f"http://{HOST}.evil.example:{dash.port}",
                                         "X-Mpdrig-Token": token}, ""),
        "https (the dashboard serves http only)": ({"Origin": f"https://{HOST}:{dash.port}",
                                                    "X-Mpdrig-Token": token}, ""),
        "a foreign Referer and no Origin, with the right token":
            ({"Referer": evil + "/attack.html", "X-Mpdrig-Token": token}, ""),
        "neither Origin nor Referer, with the right token": ({"X-Mpdrig-Token": token}, ""),
        "our Origin without the token": ({"Origin": own}, ""),
        "our Origin with a wrong token": ({"Origin": own, "X-Mpdrig-Token": "1" * 32}, ""),
    }
    failures = []
    for what, (headers, body) in refused.items():
        status, text, _ = dash.request("POST", shadow, headers=headers, body=body)
        try:
            reply = json.loads(text)
        except ValueError:
            reply = {}
        ok = status == 403 and reply.get("ok") is False and "refused" in reply.get("error", "")
        print(f"{'ok ' if ok else 'BAD'} {what}: {status} {text}", flush=True)
        if not ok:
            failures.append(f"{what}: {status} {text}")
    assert not failures, "writes not refused with 403:\n  " + "\n  ".join(failures)
    assert match, "the page carries no mpdrig-token"
    # As the page writes (fetch from its own origin, with its token): past the guard, to the
    # feed, which says that no shadow listens on this domain.
    for what, headers in {"page, Origin": {"Origin": own, "X-Mpdrig-Token": token},
                          "page by localhost": {"Origin": f"http://localhost:{dash.port}",
                                                "X-Mpdrig-Token": token},
                          "page by LocalHost": {"Origin": f"http://LocalHost:{dash.port}",
                                                "X-Mpdrig-Token": token},
                          "page, Referer only": {"Referer": own + "/?rig=mystery",
                                                 "X-Mpdrig-Token": token}}.items():
        status, text, _ = dash.request("POST", shadow, headers=headers, body="")
        print(f"{what}: {status} {text}", flush=True)
        assert status == 400 and "no shadow model is listening" in text, (what, status, text)


def check_slow(dash):
    count, period_s, lines = 50, 2.0, 6  # at most 12 s of trickling
    dash.timed_get("before", 2.0)
    slow = []
    for i in range(count):
        sock = connect(dash.port)
        sock.sendall(f"GET /api/health HTTP/1.1\r\nHost: {HOST}:{dash.port}\r\n".encode())
        slow.append(sock)
    started = time.monotonic()
    cut_at = {}
    took = []
    for line in range(lines):
        time.sleep(0.5)
        took.append(dash.timed_get(f"{count} slow clients connected, t = "
                                   f"{time.monotonic() - started:.1f} s", 1.0))
        time.sleep(period_s - 0.5)
        for i, sock in enumerate(slow):
            if i in cut_at:
                continue
            try:
                sock.sendall(f"X-Slow-{line}: {i}\r\n".encode())
            except OSError:
                cut_at[i] = time.monotonic() - started
                continue
            if closed_by_server(sock):
                cut_at[i] = time.monotonic() - started
        if len(cut_at) == count:
            break
    for sock in slow:
        sock.close()
    print(f"normal request with {count} slow clients: max {max(took) * 1000:.1f} ms over "
          f"{len(took)} tries", flush=True)
    assert len(cut_at) == count, f"only {len(cut_at)} of {count} slow clients were cut off " \
                                 f"within {time.monotonic() - started:.0f} s"
    print(f"slow clients cut off after {min(cut_at.values()):.1f}-{max(cut_at.values()):.1f} s",
          flush=True)
    assert max(cut_at.values()) < 5.0 + period_s + 2.0  # a tick of looking, and a loaded machine


def check_idle(dash):
    count = 200
    idle = [connect(dash.port) for _ in range(count)]
    started = time.monotonic()
    time.sleep(0.3)
    took = dash.timed_get(f"{count} idle connections open", 1.0)
    page_status, _, page_took = dash.request("GET", "/", timeout_s=1.0)
    print(f"GET / -> {page_status} in {page_took * 1000:.1f} ms", flush=True)
    assert page_status == 200 and took < 1.0
    closed_at = {}
    while len(closed_at) < count and time.monotonic() - started < 5.0 + 2.0:
        time.sleep(0.2)
        for i, sock in enumerate(idle):
            if i not in closed_at and closed_by_server(sock):
                closed_at[i] = time.monotonic() - started
    for sock in idle:
        sock.close()
    assert len(closed_at) == count, f"only {len(closed_at)} of {count} idle connections were " \
                                    f"closed within 7 s"
    print(f"idle connections closed after {min(closed_at.values()):.1f}-"
          f"{max(closed_at.values()):.1f} s", flush=True)
    dash.timed_get("after", 1.0)


def check_big_body(dash):
    declared = 200 * 1000 * 1000
    dash.timed_get("before", 2.0)
    rss_before = dash.rss_kb()
    sock = connect(dash.port)
    sock.sendall((f"POST /api/shadow?rig=mystery&action=set&arg=c%3D400 HTTP/1.1\r\n"
                  f"Host: {HOST}:{dash.port}\r\nContent-Type: text/plain\r\n"
                  f"Content-Length: {declared}\r\n\r\n").encode())
    started = time.monotonic()
    sock.settimeout(1.0)
    try:
        answer = sock.recv(65536).decode(errors="replace")
    except socket.timeout:
        answer = ""
    print(f"declared {declared} bytes: {answer.splitlines()[:1]} after "
          f"{(time.monotonic() - started) * 1000:.1f} ms", flush=True)
    # Push the body anyway, 1 MB at a time, for at most 5 s: it must not be kept.
    sent = 0
    sock.settimeout(0.5)
    chunk = b"x" * (1 << 20)
    while sent < declared and time.monotonic() - started < 5.0:
        try:
            sent += sock.send(chunk)
        except (socket.timeout, BlockingIOError):
            continue
        except OSError:
            break
    sock.close()
    rss_after = dash.rss_kb()
    print(f"client pushed {sent / 1e6:.0f} MB; dashboard VmRSS {rss_before / 1024:.1f} -> "
          f"{rss_after / 1024:.1f} MB", flush=True)
    assert answer.startswith("HTTP/1.1 413"), f"no 413 within 1 s of the head: {answer[:200]!r}"
    assert "Content-Length" in answer and '"ok":false' in answer
    assert rss_after - rss_before < 16 * 1024, "the body was kept"
    # A chunked body: no length, refused before any of it is read.
    status, text, _ = dash.request("POST", "/api/shadow?rig=mystery",
                                   body=iter([b"x" * 1000] * 3), timeout_s=2.0)
    print(f"chunked: {status} {text}", flush=True)
    assert status == 411
    dash.timed_get("after", 1.0)


def check_cross_site_shadow(dash, mpdrig_exe, domain):
    rig, wanted = "mystery", "wave_speed_mps=400"
    started = time.monotonic()
    procs = [subprocess.Popen([mpdrig_exe, "serve", "--clock", "realtime", "--rate-hz", "50",
                               "--domain", str(domain), "--rig", rig, "--cells", "20",
                               "--duration", "40"], stdout=subprocess.DEVNULL,
                              pass_fds=(claims[domain],)),
             subprocess.Popen([mpdrig_exe, "shadow", "--rig", rig, "--domain", str(domain),
                               "--cells", "20", "--window-s", "2", "--warmup-s", "1",
                               "--status-period-s", "0.2", "--duration", "40"],
                              stdout=subprocess.DEVNULL, pass_fds=(claims[domain],))]
    try:
        def shadow_status():
            _, text, _ = dash.request("GET", f"/api/state?rig={rig}&since=999999999")
            return json.loads(text).get("shadow_status")

        status = None
        while status is None and time.monotonic() - started < 15:
            time.sleep(0.3)
            status = shadow_status()
        assert status, "the shadow's status did not reach the dashboard within 15 s"
        print(f"shadow up after {time.monotonic() - started:.1f} s: {status['parameters']}",
              flush=True)
        assert wanted not in status["parameters"]
        path = f"/api/shadow?rig={rig}&action=set&arg={wanted.replace('=', '%3D')}"
        status_code, text, _ = dash.request("POST", path, body=wanted, headers={
            "Origin": "http://evil.example", "Content-Type": "text/plain"})
        print(f"another site's text/plain POST: {status_code} {text}", flush=True)
        time.sleep(2.0)  # ten status periods: what the shadow took would show
        status = shadow_status()
        print(f"2 s later the shadow has: {status['parameters']}", flush=True)
        assert wanted not in status["parameters"], "another site's POST set the wave speed"
        assert status_code == 403
        _, page, _ = dash.request("GET", "/")
        token = re.search(r'name="mpdrig-token" content="([0-9a-f]+)"', page).group(1)
        status_code, text, _ = dash.request("POST", path, body="", headers={
            "Origin": dash.origin, "X-Mpdrig-Token": token})
        print(f"the page's POST: {status_code} {text}", flush=True)
        assert status_code == 200 and json.loads(text)["ok"], text
        command_id = json.loads(text)["command_id"]
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline:
            status = shadow_status()
            if status["last_command_id"] == command_id and wanted in status["parameters"]:
                break
            time.sleep(0.2)
        print(f"the shadow then has: {status['parameters']}", flush=True)
        assert wanted in status["parameters"], "the page's write did not reach the shadow"
    finally:
        for proc in procs:
            proc.terminate()
        for proc in procs:
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()


CHECKS = {"cross_site": check_cross_site, "slow": check_slow, "idle": check_idle,
          "big_body": check_big_body}


def main():
    shadowed = len(sys.argv) == 4 and sys.argv[2] == "cross_site_shadow"
    if not shadowed and (len(sys.argv) != 3 or sys.argv[2] not in CHECKS):
        print(__doc__)
        return 2
    domain = claim_test_domain()
    dash = Dashboard(sys.argv[1], domain)
    try:
        if shadowed:
            check_cross_site_shadow(dash, sys.argv[3], domain)
        else:
            CHECKS[sys.argv[2]](dash)
    finally:
        dash.stop()
    print(f"{sys.argv[2]}: passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
