"""Talk to an mpdrig rig (the virtual twin of the NTNU MPD heave lab rig) from Python.

A rig is what ``mpdrig serve`` runs (or the lab's rig behind a bridge that speaks the same DDS
topics). Everything is in lab units: pressures in bar gauge, flows in L/min, the choke in
degrees (0 closed .. 90 open), positions in metres, time in seconds of rig time.

    import mpdrig
    rig = mpdrig.Rig("rig-1", domain=0)       # waits up to 10 s for the rig
    s = rig.sensors()                          # the newest sample: s.PT1_barg, s.C2_barg, ...
    rig.choke(30.0)                            # choke opening reference [deg]
    for s in rig.stream(max_samples=500):      # every sample in order (lockstep: one step each)
        rig.choke(30.0 + 0.1 * (s.PT1_barg - 4.0))

On a lockstep rig (``mpdrig serve --clock lockstep``) nothing happens until you step it:
``rig.step(10)`` advances ten sensor periods, applying every command sent before.

Errors are exceptions: ``TimeoutError`` (nothing within ``timeout`` seconds), ``RigLost`` (the
rig restarted, left or went silent: start again with a new Rig), ``RigError`` (anything else).
A command the rig refuses (NaN, out of range) is not an exception here (the rig decides, and
keeps its last valid command): ``rig.rejections()`` and ``rig.status()`` report it.
"""

from __future__ import annotations

import os
from typing import Iterator, Optional, Union

from ._mpdrig import Estimate, Profile, RigError, RigLost, Sensors, Status, Tick
from ._mpdrig import _Loop, _Rig

__all__ = ["Rig", "Sensors", "Estimate", "Tick", "Profile", "Status", "RigError", "RigLost"]

_PISTON_HOLD, _PISTON_POSITION, _PISTON_SINE, _PISTON_SWEEP = 0, 1, 2, 3
_ESTIMATES = {None: 0, "newest": 1, "paired": 2}


class Rig(_Rig):
    """One rig of an ``mpdrig serve`` (or the lab's bridge), reached over DDS.

    Rig(rig_id="rig-1", domain=0, *, strength=0, timeout=10.0, dds_config="", security=None)

    - ``rig_id``: the rig's id (``mpdrig serve --rig ID``; default service: "rig-1").
    - ``domain``: the DDS domain id (``mpdrig serve --domain N``), 0..232.
    - ``strength``: ownership strength of this client's commands. Of several controllers of
      one actuator the strongest live one wins; when it closes or dies the next takes over.
    - ``timeout``: seconds to wait for the rig, a sample, a step; after the first sample, this
      long without one means the rig is lost (``RigLost``).
    - ``dds_config``: Cyclone DDS XML (default: loopback only, 127.0.0.1).
    - ``security``: DDS Security for a class: your identity directory, made by
      ``deploy/security/make-class OUT NAME`` (``OUT/NAME``), as ``bhp_controller --security``
      takes it. The rig's topics are then in partition ``rig.<rig_id>``; your permissions say
      which rigs you may read and command (a refusal raises ``RigError`` saying so). The
      service runs ``mpdrig serve --security OUT/service``.

    Reading: ``sensors()`` (newest sample), ``next_sensors()`` (next in order), ``stream()``,
    ``ticks()`` (a controller's loop: a sample and its estimate per tick, lockstep stepped),
    ``estimate()`` (the observer's BHP estimate and heave), ``profile()`` (pressure along the
    pipe, numpy arrays), ``status()``, ``rejections()``.
    Commands: ``choke(deg)``, ``pump(lpm)``, ``outlet(barg)``, ``piston_hold()``,
    ``piston_position(m)``, ``piston_sine(amplitude_m, frequency_hz)``, ``piston_sweep(...)``.
    Lockstep: ``step(n)``. Leaving: ``close()``, or use ``with mpdrig.Rig(...) as rig:``.

    ``timeout=0`` waits for ever (and silence alone never loses the rig).

    A Rig is for one thread at a time (its calls wait without holding the GIL); several Rigs,
    even of the same rig, may live in one process.
    """

    def __init__(self, rig_id: str = "rig-1", domain: int = 0, *, strength: int = 0,
                 timeout: float = 10.0, dds_config: str = "",
                 security: Union[str, "os.PathLike[str]", None] = None) -> None:
        super().__init__(rig_id, domain, strength=strength, timeout=timeout,
                         dds_config=dds_config,
                         security="" if security is None else os.fspath(security))

    def sensors(self, fresh: bool = False) -> Sensors:
        """The newest sample that has arrived (older unread ones are dropped).

        Waits up to ``timeout`` if none has arrived yet or, with ``fresh=True``, if none has
        arrived since the last sample returned. A loop that must see every sample uses
        ``stream()`` or ``next_sensors()`` instead.
        """
        return super().sensors(fresh)

    def next_sensors(self) -> Sensors:
        """The next sample in order (waits up to ``timeout``). Keeps up to 10000 unread."""
        return super().next_sensors()

    def pending(self) -> list[Sensors]:
        """Every sample that has arrived and not been returned yet, in order, without waiting.

        After ``step(100)``: the 100 samples of those steps.
        """
        return super().pending()

    def estimate(self, sample_counter: Optional[int] = None) -> Estimate:
        """The observer's estimate for ``sample_counter`` (waits for it), or the newest one.

        The service runs the backstepping observer (thesis ch. 10) on C2 and FT1 only and
        publishes one estimate per sample, right after it: ``BHP_est_barg``,
        ``piston_velocity_est_mps``, ``piston_position_est_m``, ``disturbance_frequency_hz``.
        """
        return super().estimate(sample_counter)

    def profile(self) -> Profile:
        """The newest pressure profile along the pipe (numpy arrays; ``serve --profile-hz``)."""
        return super().profile()

    def status(self) -> Status:
        """The rig's newest status: clock, rig time, refused commands and why, warnings,
        which controller owns each actuator."""
        return super().status()

    def rejections(self) -> tuple[int, str]:
        """``(count, last_reason)`` of the commands the rig refused since the last call.

        The rig refuses NaN, infinite or out-of-range commands (choke 0..90 deg, pump 0..60
        L/min, outlet -0.5..16 barg, piston within +-0.6 m and 2 Hz) and keeps running on the
        last valid one. On a lockstep rig the refusal shows once a step has taken the command.
        """
        return super().rejections()

    def choke(self, opening_deg: float) -> None:
        """Choke opening reference [deg], 0 closed .. 90 open (through the actuator's lag).

        Opening the choke lowers the pressure upstream of it (C2) and the bottom-hole pressure.
        The first command of a kind waits until the rig's reader has matched (up to ``timeout``).
        """
        super().choke(opening_deg)

    def pump(self, flow_lpm: float) -> None:
        """Back-pressure pump flow [L/min], 0..60."""
        super().pump(flow_lpm)

    def outlet(self, pressure_barg: float) -> None:
        """Pressure downstream of the choke (C1) [barg], -0.5..16."""
        super().outlet(pressure_barg)

    def piston_hold(self) -> None:
        """Heave generator: stay where it is."""
        self._piston(_PISTON_HOLD, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    def piston_position(self, position_m: float) -> None:
        """Heave generator: go to ``position_m`` [m] (stream these for your own heave profile)."""
        self._piston(_PISTON_POSITION, position_m, 0.0, 0.0, 0.0, 0.0, 0.0)

    def piston_sine(self, amplitude_m: float, frequency_hz: float, mean_m: float = 0.0) -> None:
        """Heave generator: ``mean_m + amplitude_m sin(2 pi frequency_hz t)``, made by the rig."""
        self._piston(_PISTON_SINE, 0.0, mean_m, amplitude_m, frequency_hz, 0.0, 0.0)

    def piston_sweep(self, amplitude_m: float, start_hz: float, end_hz: float,
                     duration_s: float, mean_m: float = 0.0) -> None:
        """Heave generator: a linear chirp from ``start_hz`` to ``end_hz`` over ``duration_s``."""
        self._piston(_PISTON_SWEEP, 0.0, mean_m, amplitude_m, start_hz, end_hz, duration_s)

    def step(self, steps: int = 1) -> Sensors:
        """Lockstep rig only: advance ``steps`` sensor periods and return the last sample.

        Every command sent before is acknowledged by the rig first, so it applies from the
        first of these steps: a lockstep controller is deterministic however loaded the
        machine is. All the samples of the steps are in ``pending()`` (and ``next_sensors()``).
        """
        return super().step(steps)

    def stream(self, max_samples: Optional[int] = None) -> Iterator[Sensors]:
        """Every sample in order, forever or ``max_samples`` of them.

        On a lockstep rig each iteration first steps the rig once, so the same loop
        ``for s in rig.stream(): rig.choke(...)`` controls a real-time and a lockstep rig (in
        lockstep each command applies from the next sample on). Ends with ``RigLost`` if the
        rig is lost and ``TimeoutError`` if no sample comes for ``timeout`` seconds. The client
        library's control loop (``ticks(every_sample=True)``) runs it.
        """
        if max_samples is not None and max_samples <= 0:
            return
        n = 0
        for tick in self.ticks(every_sample=True):
            yield tick.sensors
            n += 1
            if max_samples is not None and n >= max_samples:
                return  # before the next tick: a lockstep rig is not stepped once more

    def ticks(self, duration_s: Optional[float] = None, *, estimates: Optional[str] = None,
              every_sample: bool = False) -> Iterator[Tick]:
        """The ticks of a controller: the client library's control loop, as the C++ clients run it.

        Each tick is ``tick.sensors``, ``tick.estimate`` and ``tick.dt_s`` (rig time since the
        last tick). On a lockstep rig each tick steps the rig once, after the commands of the
        last tick are acknowledged (deterministic); on a real-time rig each tick is the newest
        sample (a controller that falls behind skips samples), or every sample in order with
        ``every_sample=True`` (what ``stream()`` does).

        - ``duration_s``: the rig time at which the run ends, after the tick at or past it
          (None: no end).
        - ``estimates``: None; ``"newest"``, the newest estimate that has arrived (or None);
          ``"paired"``, the estimate of the tick's own sample in lockstep (waiting for it), the
          newest in real time, ticks before the first skipped.

        Ends with ``RigLost`` if the rig is lost (or its service ends its run), ``TimeoutError``
        if no sample comes for ``timeout`` seconds, ``KeyboardInterrupt`` at Ctrl-C.
        """
        if estimates not in _ESTIMATES:
            raise ValueError("estimates must be None, 'newest' or 'paired'")
        loop = _Loop(self, 0.0 if duration_s is None else float(duration_s),
                     every_sample=every_sample, estimates=_ESTIMATES[estimates])
        while True:
            tick = loop.next(self)
            if tick is None:
                return
            yield tick

    def __enter__(self) -> "Rig":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        try:
            state = "closed" if self.closed else ("lost" if self.lost else "connected")
        except Exception:  # a Rig whose __init__ failed (tracebacks print its repr)
            return "<mpdrig.Rig (not connected)>"
        clock = "lockstep" if self.lockstep else "real time"
        return (f"<mpdrig.Rig {self.rig_id!r} domain={self.domain} {clock} "
                f"strength={self.strength} {state}>")
