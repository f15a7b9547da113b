#!/usr/bin/env python3
"""What the dashboard costs: the service's CPU with the dashboard absent, idle and watched, and
whether the dashboard keeps up with many rigs.

One `mpdrig serve` runs RIGS rigs at RATE_HZ in real time (loopback DDS, heave on, the observer
and the pressure profile on, as the demo). Three phases of PHASE_S seconds each:
  absent   no dashboard
  idle     `dashboard` running, nobody watching (no request: it has no DDS participant)
  watched  every rig's page state fetched 10 times a second (as RIGS browsers would), which keeps
           the dashboard's readers open on every topic of every rig
For each phase: the service's and the dashboard's CPU (utime + stime from /proc, in % of one
core), and while watched: the age of the newest sensor sample each answer shows (the dashboard's
`age_ms`: now minus the sample's write time) plus the answer's own round trip, and the sensor
samples the dashboard took per rig and second (RATE_HZ if it keeps up with every sample).

With --browser, a fourth phase: the page itself in Debian's headless Chromium (Selenium), on
rig-1: the CPU of the service, the dashboard and Chromium (all its processes), and the age of the
newest sample when the page drew it.

  bench/dashboard_cost.py [--rigs 10] [--rate-hz 100] [--phase-s 20] [--domain 97]
                          [--build build] [--browser]
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time
import urllib.request

TICK_S = 1.0 / os.sysconf("SC_CLK_TCK")


def cpu_s(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) * TICK_S  # utime, stime


def get_json(url):
    started = time.monotonic()
    with urllib.request.urlopen(url, timeout=5) as reply:
        body = json.loads(reply.read())
    return body, time.monotonic() - started


def measure(pids, seconds, during=None):
    """CPU of each pid (all its threads) over `seconds` of wall time, in % of one core; `during`
    runs meanwhile."""
    start = {name: cpu_s(pid) for name, pid in pids.items()}
    t0 = time.monotonic()
    extra = during(seconds) if during else time.sleep(seconds)
    wall = time.monotonic() - t0
    return {name: 100.0 * (cpu_s(pid) - start[name]) / wall for name, pid in pids.items()}, extra


def watch(url, rigs, seconds):
    """Polls every rig's state at 10 Hz for `seconds`: ages, round trips, samples per rig."""
    ages, trips, first, last = [], [], {}, {}
    since = {rig: 0 for rig in rigs}
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        tick = time.monotonic()
        for rig in rigs:
            state, trip = get_json(f"{url}api/state?rig={rig}&since={since[rig]}")
            if not state.get("known") or "sensors" not in state:
                continue
            since[rig] = int(state.get("seq", 0))
            ages.append(state["sensors"]["age_ms"] + 1000.0 * trip)
            trips.append(1000.0 * trip)
            status = state.get("status", {})
            now = (time.monotonic(), state["samples"], state["sensors"]["counter"],
                   status.get("lost_periods", 0))
            first.setdefault(rig, now)
            last[rig] = now
        time.sleep(max(0.0, 0.1 - (time.monotonic() - tick)))
    # Per rig: samples the dashboard took per second, samples the rig sent per second (its
    # counter), periods the rig itself lost (a rig starved of CPU sends fewer).
    rates = [((last[r][1] - first[r][1]) / (last[r][0] - first[r][0]),
              (last[r][2] - first[r][2]) / (last[r][0] - first[r][0]), last[r][3] - first[r][3])
             for r in first if last[r][0] > first[r][0]]
    return ages, trips, rates


def children(pid):
    """Every descendant process of `pid` (Chromium runs a dozen), from the parents in /proc."""
    parent_of = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    parent_of[int(entry)] = int(f.read().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                pass
    found, todo = [], [pid]
    while todo:
        parent = todo.pop()
        kids = [p for p, pp in parent_of.items() if pp == parent]
        found += kids
        todo += kids
    return found


def browser_phase(url, pids, seconds, watched_serve, absent_serve):
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1500,1400"):
        options.add_argument(arg)
    driver_service = Service("/usr/bin/chromedriver")
    browser = webdriver.Chrome(service=driver_service, options=options)
    try:
        browser.get(url + "?rig=rig-1")
        time.sleep(5.0)  # the page loads and the charts fill
        tree = children(driver_service.process.pid)
        browser_cpu0 = sum(cpu_s(p) for p in tree if os.path.exists(f"/proc/{p}"))
        frames0 = browser.execute_script("return window.mpdrigDashboard.frames;")

        def sample(duration):
            ages, end = [], time.monotonic() + duration
            while time.monotonic() < end:
                ages.append(browser.execute_script("return window.mpdrigDashboard.shownAgeMs;"))
                time.sleep(0.2)
            return [a for a in ages if a is not None]

        cpu, ages = measure(pids, seconds, sample)
        browser_cpu = sum(cpu_s(p) for p in tree if os.path.exists(f"/proc/{p}")) - browser_cpu0
        frames = browser.execute_script("return window.mpdrigDashboard.frames;") - frames0
        print(f"  chromium: serve {cpu['serve']:5.2f} %, dashboard {cpu['dashboard']:4.2f} %, "
              f"chromium {100.0 * browser_cpu / seconds:.1f} % (the page drew "
              f"{frames / seconds:.1f} frames/s)")
        if ages:
            print(f"  newest sample's age when the page drew it: median "
                  f"{statistics.median(ages):.0f} ms, p95 {pct(ages, 0.95):.0f} ms, max "
                  f"{max(ages):.0f} ms")
    finally:
        browser.quit()


def pct(values, q):
    values = sorted(values)
    return values[min(len(values) - 1, int(q * len(values)))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rigs", type=int, default=10)
    parser.add_argument("--rate-hz", type=float, default=100.0)
    parser.add_argument("--phase-s", type=float, default=20.0)
    parser.add_argument("--domain", type=int, default=97)
    parser.add_argument("--build", default=os.path.join(os.path.dirname(__file__), "..", "build"))
    parser.add_argument("--browser", action="store_true",
                        help="also watch rig-1 in headless Chromium (needs python3-selenium)")
    args = parser.parse_args()
    mpdrig = os.path.join(args.build, "tools", "mpdrig")
    dashboard = os.path.join(args.build, "clients", "dashboard")
    rigs = [f"rig-{i + 1}" for i in range(args.rigs)]
    serve_args = [mpdrig, "serve", "--clock", "realtime", "--rate-hz", str(args.rate_hz),
                  "--domain", str(args.domain), "--heave-amp-m", "0.1", "--heave-hz", "0.2",
                  "--pump-lpm", "5"]
    for rig in rigs:
        serve_args += ["--rig", rig]
    serve = subprocess.Popen(serve_args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    dash = None
    try:
        time.sleep(5.0)  # the rigs start
        print(f"{args.rigs} rigs at {args.rate_hz:g} Hz in one `mpdrig serve` (real time), "
              f"{args.phase_s:g} s per phase, CPU in % of one core; load average "
              f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
        absent, _ = measure({"serve": serve.pid}, args.phase_s)
        print(f"  absent : serve {absent['serve']:5.2f} %")

        dash = subprocess.Popen([dashboard, "--domain", str(args.domain), "--port", "0",
                                 "--idle-s", "5"], stdout=subprocess.PIPE, text=True)
        url = re.search(r"(http://[0-9.]+:\d+/)", dash.stdout.readline()).group(1)
        time.sleep(2.0)
        pids = {"serve": serve.pid, "dashboard": dash.pid}
        idle, _ = measure(pids, args.phase_s)
        health, _ = get_json(url + "api/health")
        print(f"  idle   : serve {idle['serve']:5.2f} %, dashboard {idle['dashboard']:4.2f} % "
              f"(DDS {health['dds']})")

        get_json(url + "api/rigs")
        time.sleep(3.0)  # DDS opens and the rigs' statuses arrive
        watched, (ages, trips, rates) = measure(pids, args.phase_s,
                                                lambda s: watch(url, rigs, s))
        print(f"  watched: serve {watched['serve']:5.2f} %, dashboard {watched['dashboard']:4.2f} %"
              f" ({len(trips)} answers, {len(trips) / args.phase_s:.0f}/s)")
        if ages:
            print(f"  newest sample's age when the answer arrives: median "
                  f"{statistics.median(ages):.0f} ms, p95 {pct(ages, 0.95):.0f} ms, max "
                  f"{max(ages):.0f} ms (answer round trip median {statistics.median(trips):.1f} ms)")
        if rates:
            taken = [r[0] for r in rates]
            sent = [r[1] for r in rates]
            missed = sum(r[1] - r[0] for r in rates) / sum(sent)
            print(f"  sensor samples per rig and second: the rigs sent {min(sent):.1f} .. "
                  f"{max(sent):.1f}, the dashboard took {min(taken):.1f} .. {max(taken):.1f} "
                  f"({100 * missed:.2f} % not taken); periods the rigs lost meanwhile: "
                  f"{sum(r[2] for r in rates)}")
        print(f"  the service: idle - absent = {idle['serve'] - absent['serve']:+.2f} %, "
              f"watched - absent = {watched['serve'] - absent['serve']:+.2f} %")
        if args.browser:
            browser_phase(url, pids, args.phase_s, watched["serve"], absent["serve"])
        print(f"  load average at the end: {os.getloadavg()[0]:.1f}")
        return 0
    finally:
        for proc in (dash, serve):
            if proc and proc.poll() is None:
                proc.terminate()
                proc.wait(timeout=10)


if __name__ == "__main__":
    sys.exit(main())
