#!/usr/bin/env python3
"""Live plot of a rig: PT1 and the observer's BHP estimate, C2, the choke, and the pressure
profile along the pipe, with matplotlib.

    python3 live_plot.py --rig rig-1 --domain 0 --window 30

A real-time rig only (a lockstep rig waits for someone to step it).
"""

from __future__ import annotations

import argparse
import collections
import sys

import matplotlib.pyplot as plt
from matplotlib.animation import FuncAnimation

import mpdrig


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rig", default="rig-1")
    parser.add_argument("--domain", type=int, default=0)
    parser.add_argument("--window", type=float, default=30.0, help="seconds of history shown")
    args = parser.parse_args()
    try:
        rig = mpdrig.Rig(args.rig, domain=args.domain)
    except (mpdrig.RigError, TimeoutError) as error:
        print(f"live_plot.py: {error}", file=sys.stderr)
        return 1
    history = collections.deque()
    fig, (ax_p, ax_c, ax_x) = plt.subplots(3, 1, figsize=(9, 9))
    (pt1,) = ax_p.plot([], [], label="PT1 (bottom) [barg]")
    (bhp_est,) = ax_p.plot([], [], "--", label="BHP estimate [barg]")
    (c2,) = ax_p.plot([], [], label="C2 (choke inlet) [barg]")
    ax_p.legend(loc="upper left")
    (choke,) = ax_c.plot([], [], label="choke [deg]")
    ax_c.legend(loc="upper left")
    (profile,) = ax_x.plot([], [], label="pressure [barg]")
    (profile_est,) = ax_x.plot([], [], "--", label="estimate [barg]")
    ax_x.set_xlabel("position from the bottom [m]")
    ax_x.legend(loc="upper right")

    def update(_frame):
        for s in rig.pending():
            history.append((s.time_s, s.PT1_barg, s.C2_barg, s.choke_position_deg))
        if not history:
            return []
        while history and history[-1][0] - history[0][0] > args.window:
            history.popleft()
        t, p1, p2, ch = zip(*history)
        pt1.set_data(t, p1)
        c2.set_data(t, p2)
        choke.set_data(t, ch)
        try:
            est = rig.estimate()
            times, values = list(bhp_est.get_xdata()), list(bhp_est.get_ydata())
            times.append(est.time_s)
            values.append(est.BHP_est_barg)
            keep = [i for i, x in enumerate(times) if x >= t[0]]
            bhp_est.set_data([times[i] for i in keep], [values[i] for i in keep])
            prof = rig.profile()
            profile.set_data(prof.position_m, prof.pressure_barg)
            if len(prof.pressure_est_barg):
                profile_est.set_data(prof.position_m, prof.pressure_est_barg)
        except TimeoutError:
            pass  # a service without observer or profile: plot the rest
        for ax in (ax_p, ax_c, ax_x):
            ax.relim()
            ax.autoscale_view()
        return [pt1, bhp_est, c2, choke, profile, profile_est]

    # Kept in a name: an animation that is garbage-collected stops.
    animation = FuncAnimation(fig, update, interval=100, cache_frame_data=False)
    try:
        plt.show()
    except mpdrig.RigLost as lost:
        print(f"live_plot.py: {lost}", file=sys.stderr)
        return 3
    finally:
        del animation
        rig.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
