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

  bench/dashboard_cost.py [--rigs 10] [--rate-hz 100] [--phase-s 20] [--domain 97]
                          [--build build]
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
    args = parser.parse_args()
    mpdrig = os.path.join(args.build, "service", "mpdrig")
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
        print(f"  load average at the end: {os.getloadavg()[0]:.1f}")
        return 0
    finally:
        for proc in (dash, serve):
            if proc and proc.poll() is None:
                proc.terminate()
                proc.wait(timeout=10)


if __name__ == "__main__":
    sys.exit(main())
