#!/usr/bin/env python3
"""Hold a rig's bottom-hole pressure at a set point against heave with the choke, in Python.

The same control law as clients/bhp_controller.cc (its header explains it), in a page:

    e = BHP - set point                           [bar]
    choke = u_I + Kp e + Re{theta z}              [deg]   (opening the choke lowers the BHP)
    u_I' = Ki e                                   (frozen while clamped and pushing further)
    theta' = -gamma * 2 e conj(z) / |z|^2 / G^,   G^ = -g exp(-j omega tau)

PI alone cannot reject a 0.1-0.2 Hz heave: the choke acts on the bottom through 1.06 s of pipe
(l/c) plus the actuator's lag. The feed-forward term cancels the heave using the observer's
heave phasor z = v_d^ + j omega x_d^ (topic mpdrig_estimate), adapting theta until the
oscillation at omega is gone.

    mpdrig serve --clock lockstep --heave-amp-m 0.1 --heave-hz 0.2 --pump-lpm 5 \\
        --choke-deg 31 --rig fixed --rig controlled --domain 7 &
    python3 bhp_controller.py --rig fixed --domain 7 --duration 60 --open-loop
    python3 bhp_controller.py --rig controlled --domain 7 --duration 60 --use-estimate

Prints one key=value line like the C++ controller: PT1's half peak-to-peak swing, mean and
periodic RMS (the heave's swing, the sensors' noise left out) over the last --measure-last seconds.
"""

from __future__ import annotations

import argparse
import cmath
import math
import sys
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

import mpdrig


@dataclass
class Gains:
    kp_deg_per_bar: float = 0.1
    ki_deg_per_bar_s: float = 0.05
    feedforward: bool = True
    adapt_per_s: float = 0.2          # gamma: converges in about 1/gamma s
    choke_gain_bar_per_deg: float = 0.7  # g of the rough plant model G^
    delay_s: float = 1.3              # tau: l/c + actuator lag + the pipe's phase
    choke_min_deg: float = 2.0
    choke_max_deg: float = 88.0
    # Without a set point: command nothing, watch at least settle_s and two heave periods (the
    # heave's start-up, the observer's convergence), then average the BHP and the choke over
    # learn_s rounded to whole heave periods, and hold that mean BHP from that mean opening.
    settle_s: float = 10.0
    learn_s: float = 10.0


SETTLE_PERIODS = 2.0  # the observer's disturbance model converges in about two heave periods


class BhpController:
    """The control law; time and signals are arguments, the rig is elsewhere."""

    def __init__(self, gains: Gains, setpoint_barg: Optional[float] = None):
        self.g = gains
        self.setpoint_barg = setpoint_barg
        self.integral_deg: Optional[float] = None
        self.theta = 0j
        self._last_t: Optional[float] = None
        self._first_t: Optional[float] = None
        self._learn_start: Optional[float] = None
        self._learn_end: Optional[float] = None
        self._learn_sum = self._learn_choke_sum = 0.0
        self._learn_n = 0

    def _learn(self, t_s: float, bhp_barg: float, choke_deg: float, frequency_hz: float) -> bool:
        """Watch with the choke left alone; True once the set point is the mean BHP seen."""
        g = self.g
        if self._first_t is None:
            self._first_t = t_s
        settle_s = max(g.settle_s, SETTLE_PERIODS / frequency_hz if frequency_hz > 0.0 else 0.0)
        if self._learn_start is None and t_s - self._first_t < settle_s:
            return False
        if self._learn_start is None:
            self._learn_start = t_s
        if self._learn_end is None and t_s - self._learn_start >= g.learn_s:
            # Whole heave periods: a part period biases the mean.
            learn_s = g.learn_s
            if frequency_hz > 0.0:  # the nearest whole number of periods, at least one
                learn_s = max(1.0, round(g.learn_s * frequency_hz)) / frequency_hz
            self._learn_end = self._learn_start + learn_s
        if self._learn_end is not None and t_s >= self._learn_end - 1e-9:
            n = max(self._learn_n, 1)
            self.setpoint_barg = self._learn_sum / n if self._learn_n else bhp_barg
            self.integral_deg = self._learn_choke_sum / n if self._learn_n else choke_deg
            return True
        self._learn_sum += bhp_barg
        self._learn_choke_sum += choke_deg
        self._learn_n += 1
        return False

    def update(self, t_s: float, bhp_barg: float, choke_deg: float, z: complex,
               frequency_hz: float) -> Optional[float]:
        """One sample; returns the choke reference [deg], or None while it learns its set point.
        z = 0: no feed-forward this sample."""
        dt = min(max(t_s - self._last_t, 0.0), 1.0) if self._last_t is not None else 0.0
        self._last_t = t_s
        g = self.g
        if self.setpoint_barg is None and not self._learn(t_s, bhp_barg, choke_deg, frequency_hz):
            return None
        if self.integral_deg is None:  # a set point given: start from the choke's reading
            self.integral_deg = choke_deg
        e = bhp_barg - self.setpoint_barg
        heave_known = g.feedforward and frequency_hz > 0.0 and abs(z) > 1e-4
        if heave_known:
            omega = 2.0 * math.pi * frequency_hz
            plant = -g.choke_gain_bar_per_deg * cmath.exp(-1j * omega * g.delay_s)
            demodulated = 2.0 * e * z.conjugate() / (abs(z) ** 2)
            self.theta -= g.adapt_per_s * dt * demodulated / plant
        feedforward = (self.theta * z).real if heave_known else 0.0
        wanted = self.integral_deg + g.kp_deg_per_bar * e + feedforward
        command = min(max(wanted, g.choke_min_deg), g.choke_max_deg)
        pushing_up = wanted > g.choke_max_deg and e > 0.0
        pushing_down = wanted < g.choke_min_deg and e < 0.0
        if not (pushing_up or pushing_down):
            self.integral_deg += g.ki_deg_per_bar_s * e * dt
        return command


@dataclass
class Swing:
    """PT1 over the measured window: half peak-to-peak, mean, and the RMS of its periodic part
    at the heave frequency f (least squares of a mean and harmonics 1-3 of f: the sensors' noise
    is not in it, where half peak-to-peak reads about 0.07 bar of it at the lab's noise)."""
    times: list = field(default_factory=list)
    values: list = field(default_factory=list)
    frequency_hz: float = 0.0

    def add(self, t_s: float, pt1_barg: float) -> None:
        self.times.append(t_s)
        self.values.append(pt1_barg)

    @property
    def n(self) -> int:
        return len(self.values)

    @property
    def amplitude_bar(self) -> float:
        return 0.5 * (max(self.values) - min(self.values))

    @property
    def mean_barg(self) -> float:
        return sum(self.values) / len(self.values)

    def _harmonics(self) -> Optional[np.ndarray]:
        """Least-squares coefficients c0, a1, b1, a2, b2, a3, b3; None without a frequency."""
        if self.frequency_hz <= 0.0 or self.n < 28:
            return None
        t = np.asarray(self.times)
        columns = [np.ones_like(t)]
        for k in (1, 2, 3):
            w = 2.0 * math.pi * k * self.frequency_hz
            columns += [np.cos(w * t), np.sin(w * t)]
        coefficients, *_ = np.linalg.lstsq(np.column_stack(columns), np.asarray(self.values),
                                           rcond=None)
        return coefficients

    @property
    def heave_bar(self) -> float:
        """Amplitude of PT1's component at the heave frequency."""
        c = self._harmonics()
        return math.nan if c is None else math.hypot(c[1], c[2])

    @property
    def periodic_rms_bar(self) -> float:
        """RMS of PT1's periodic part (harmonics 1-3 of the heave)."""
        c = self._harmonics()
        return math.nan if c is None else math.sqrt(float(np.sum(c[1:] ** 2)) / 2.0)


def run(rig: mpdrig.Rig, duration_s: float, measure_last_s: float, *, open_loop: bool = False,
        use_estimate: bool = False, gains: Optional[Gains] = None,
        setpoint_barg: Optional[float] = None) -> Swing:
    """Controls (or, open loop, only watches) `rig` until rig time `duration_s`.

    Returns PT1's swing over the last `measure_last_s` seconds. The loop is the client library's
    (``rig.ticks``, as the C++ controllers run it): in lockstep every sample is controlled before
    the next step; in real time the controller acts on the newest sample.
    """
    gains = gains or Gains()
    wants_estimate = not open_loop and (use_estimate or gains.feedforward)
    swing = Swing()
    controller = BhpController(gains, setpoint_barg)

    def heave_frequency_hz() -> float:
        """The observer's heave frequency, for the swing's fit; 0 (RMS NaN) without an observer."""
        try:
            return rig.estimate().disturbance_frequency_hz
        except (TimeoutError, mpdrig.RigError):
            return 0.0

    if open_loop and rig.lockstep:
        # Nothing to decide between samples: step a second at a time and read them all.
        while True:
            rig.step(100)
            for s in rig.pending():
                if s.time_s > duration_s - measure_last_s and s.time_s <= duration_s + 1e-9:
                    if swing.n == 0:
                        swing.frequency_hz = heave_frequency_hz()
                    swing.add(s.time_s, s.PT1_barg)
                if s.time_s >= duration_s - 1e-9:
                    return swing
    # The client library's control loop: in lockstep one step per tick, with the estimate of
    # that very sample; in real time the newest sample and the newest estimate.
    for tick in rig.ticks(duration_s, estimates="paired" if wants_estimate else None):
        s = tick.sensors
        z, frequency_hz, bhp = 0j, 0.0, s.PT1_barg
        if wants_estimate:
            est = tick.estimate
            z = complex(est.piston_velocity_est_mps,
                        2.0 * math.pi * est.disturbance_frequency_hz * est.piston_position_est_m)
            frequency_hz = est.disturbance_frequency_hz
            if use_estimate:
                bhp = est.BHP_est_barg
        if not open_loop:
            command = controller.update(s.time_s, bhp, s.choke_position_deg, z, frequency_hz)
            if command is not None:
                rig.choke(command)
        if s.time_s > duration_s - measure_last_s:
            if swing.n == 0:  # the window's first frequency, as the C++ controller takes it
                swing.frequency_hz = frequency_hz if wants_estimate else heave_frequency_hz()
            swing.add(s.time_s, s.PT1_barg)
    return swing


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rig", default="rig-1", help="rig id (default rig-1)")
    parser.add_argument("--domain", type=int, default=0, help="DDS domain id (default 0)")
    parser.add_argument("--duration", type=float, default=60.0, help="stop at this rig time [s]")
    parser.add_argument("--measure-last", type=float, default=20.0,
                        help="report PT1's swing over the last this many seconds")
    parser.add_argument("--setpoint-barg", type=float, default=None,
                        help="BHP to hold [barg] (default: with the choke left alone, the mean "
                        "over whole heave periods after 10 s and two periods)")
    parser.add_argument("--use-estimate", action="store_true",
                        help="control the observer's BHP_est instead of PT1")
    parser.add_argument("--no-feedforward", action="store_true", help="PI only")
    parser.add_argument("--open-loop", action="store_true", help="no commands: the baseline")
    parser.add_argument("--strength", type=int, default=10, help="ownership strength")
    args = parser.parse_args()
    if not 0.0 <= args.measure_last <= args.duration:
        parser.error("--measure-last must be within --duration")
    gains = Gains(feedforward=not args.no_feedforward)
    try:
        with mpdrig.Rig(args.rig, domain=args.domain, strength=args.strength) as rig:
            swing = run(rig, args.duration, args.measure_last, open_loop=args.open_loop,
                        use_estimate=args.use_estimate, gains=gains,
                        setpoint_barg=args.setpoint_barg)
    except mpdrig.RigLost as lost:
        print(f"bhp_controller.py: {lost}", file=sys.stderr)
        return 3
    except (mpdrig.RigError, TimeoutError) as error:
        print(f"bhp_controller.py: {error}", file=sys.stderr)
        return 1
    mode = ("fixed-choke" if args.open_loop else "pi" if args.no_feedforward
            else "pi+ff(estimate)" if args.use_estimate else "pi+ff")
    print(f"rig={args.rig} mode={mode} window_s={args.measure_last:g} samples={swing.n} "
          f"PT1_amplitude_bar={swing.amplitude_bar:.5f} PT1_mean_barg={swing.mean_barg:.5f} "
          f"PT1_heave_bar={swing.heave_bar:.5f} PT1_periodic_rms_bar={swing.periodic_rms_bar:.5f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
