"""mpdrig.Rig against a lockstep `mpdrig serve`: reading, commands and their effect, refused
commands, ownership strength, and the errors a student meets first."""

from __future__ import annotations

import math
import signal
import subprocess
import sys

import numpy as np
import pytest

import mpdrig

# 100 Hz, no sensor noise (deterministic values), no heave: the pipe at rest under the pump's flow.
RIG_ARGS = ("--clock", "lockstep", "--rate-hz", "100", "--pump-lpm", "5", "--choke-deg", "31",
            "--sensor-noise", "none", "--rig", "r1")
PERIOD_S = 0.01


def test_reads_every_lab_channel_in_lab_units(serve):
    service = serve(*RIG_ARGS)
    with mpdrig.Rig("r1", domain=service.domain, timeout=20) as rig:
        assert rig.lockstep
        first = rig.step(10)
        arrived = rig.pending()
        # step(10) published ten samples, in order, one period apart; it returns the last.
        assert len(arrived) == 10
        counters = [s.sample_counter for s in arrived]
        assert counters == list(range(counters[0], counters[0] + 10))
        assert np.allclose(np.diff([s.time_s for s in arrived]), PERIOD_S, atol=1e-9)
        assert first.sample_counter == arrived[-1].sample_counter
        s = rig.step(100)
        assert s.sample_counter == first.sample_counter + 100
        assert s.time_s == pytest.approx(first.time_s + 100 * PERIOD_S, abs=1e-9)
        # The profile array is the ten properties, and the rig-log row has the same values.
        assert isinstance(s.PT_barg, np.ndarray) and s.PT_barg.shape == (10,)
        assert s.PT_barg.tolist() == [getattr(s, f"PT{i}_barg") for i in range(1, 11)]
        row = s.as_dict()
        assert row["PT10_barg"] == s.PT10_barg and row["FT2_lpm"] == s.FT2_lpm
        # Lab units: the pump runs 5 L/min (FT2 is the command, an input); the choke sits at
        # 31 deg; the pipe rises 2.3 m from PT1 to PT10, so at rest PT1 - PT10 is the water
        # column, rho g h = 1000 * 9.81 * 2.3 Pa = 0.226 bar (friction needs flow: the piston
        # is still). A value in Pa or bar absolute would miss these by orders or by 1 bar.
        assert s.FT2_lpm == pytest.approx(5.0, abs=1e-6)
        assert s.choke_position_deg == pytest.approx(31.0, abs=0.01)
        assert s.PT1_barg - s.PT10_barg == pytest.approx(0.226, abs=0.02)
        assert 0.5 < s.C2_barg < 16.0
        status = rig.status()
        assert status.clock == "lockstep" and status.sim_time_s == pytest.approx(s.time_s)
        est = rig.estimate(s.sample_counter)
        assert est.sample_counter == s.sample_counter
        # The observer, from C2 and FT1 alone, finds the bottom-hole pressure of a rig at rest.
        assert est.BHP_est_barg == pytest.approx(s.PT1_barg, abs=0.05)


def test_choke_command_moves_c2_the_right_way(serve):
    service = serve(*RIG_ARGS)
    with mpdrig.Rig("r1", domain=service.domain, timeout=20) as rig:
        at_31 = rig.step(300).C2_barg  # settled: 3 s at the start opening
        rig.choke(45.0)                # opening lets the pump's flow out with less pressure
        opened = rig.step(300)
        rig.choke(20.0)                # closing holds it back
        closed = rig.step(300)
        print(f"C2: 31 deg {at_31:.3f}, 45 deg {opened.C2_barg:.3f}, "
              f"20 deg {closed.C2_barg:.3f} barg")
        assert opened.choke_position_deg == pytest.approx(45.0, abs=0.5)
        assert closed.choke_position_deg == pytest.approx(20.0, abs=0.5)
        # 5 L/min through the choke drops 3.4 bar at 31 deg; the characteristic G(theta) grows
        # with the opening, so C2 - C1 falls at 45 deg and rises at 20 deg by a large part of it.
        assert opened.C2_barg < at_31 - 0.5
        assert closed.C2_barg > at_31 + 0.5


def test_a_refused_command_is_reported_and_the_rig_keeps_the_last_valid_one(serve):
    service = serve(*RIG_ARGS)
    with mpdrig.Rig("r1", domain=service.domain, timeout=20) as rig:
        rig.step(1)
        assert rig.rejections() == (0, "")
        rig.choke(40.0)
        rig.step(200)
        rig.choke(math.nan)
        s = rig.step(100)
        count, reason = rig.rejections()
        assert count == 1 and "choke" in reason, reason
        assert s.choke_position_deg == pytest.approx(40.0, abs=0.5)
        rig.pump(1000.0)  # out of 0..60 L/min
        s = rig.step(10)
        count, reason = rig.rejections()
        assert count == 1 and "pump" in reason, reason
        assert s.FT2_lpm == pytest.approx(5.0, abs=1e-6)
        assert rig.status().rejected_commands == 2
        # Bad arguments from Python are Python errors, not crashes.
        with pytest.raises(TypeError):
            rig.choke("wide open")
        with pytest.raises(mpdrig.RigError):
            rig.step(0)


def test_the_stronger_controller_owns_the_choke_and_the_weaker_takes_over(serve):
    service = serve(*RIG_ARGS)
    weak = mpdrig.Rig("r1", domain=service.domain, strength=10, timeout=20)
    strong = mpdrig.Rig("r1", domain=service.domain, strength=20, timeout=20)
    try:
        strong.choke(60.0)
        strong.step(1)     # the strong command acknowledged and taken
        weak.choke(20.0)   # refused by DDS ownership, not by the rig
        s = weak.step(300)
        assert s.choke_position_deg == pytest.approx(60.0, abs=0.5)
        owners = [o for o in weak.status().actuator_owners if o.startswith("choke")]
        assert owners and "strength 20" in owners[0], owners
        strong.close()     # deletes its writer, which unregisters the instance
        # The weak controller goes on commanding, as a controller does every sample; the first of
        # its commands may still meet the strong writer's ownership (the unregistration travels
        # from another participant), the next ones own the choke.
        for _ in range(300):
            weak.choke(25.0)
            s = weak.step(1)
        assert s.choke_position_deg == pytest.approx(25.0, abs=0.5)
        owners = [o for o in weak.status().actuator_owners if o.startswith("choke")]
        assert owners and "strength 10" in owners[0], owners
        with pytest.raises(mpdrig.RigError):
            strong.choke(50.0)  # closed
    finally:
        weak.close()
        strong.close()


def test_no_such_rig_is_a_timeout_and_a_real_time_rig_is_not_stepped(serve):
    service = serve("--clock", "realtime", "--rate-hz", "100", "--rig", "rt",
                    "--sensor-noise", "none")
    with pytest.raises(TimeoutError, match="no rig 'nope'"):
        mpdrig.Rig("nope", domain=service.domain, timeout=1.0)
    with mpdrig.Rig("rt", domain=service.domain, timeout=20) as rig:
        assert not rig.lockstep
        with pytest.raises(mpdrig.RigError, match="lockstep"):
            rig.step(1)
        samples = list(rig.stream(max_samples=20))
        counters = [s.sample_counter for s in samples]
        assert counters == sorted(counters) and len(set(counters)) == 20
    with pytest.raises(mpdrig.RigError):
        mpdrig.Rig("rt", domain=999)


def test_a_stopped_rig_is_lost(serve):
    service = serve(*RIG_ARGS)
    rig = mpdrig.Rig("r1", domain=service.domain, timeout=5)
    rig.step(50)
    service.stop()
    # The service left: its sensor writer is gone, and the rig is lost, not just quiet.
    with pytest.raises(mpdrig.RigLost):
        rig.step(1)
    assert rig.lost
    rig.close()


def test_ticks_run_the_client_librarys_control_loop(serve):
    """Rig.ticks() and Rig.stream() iterate the C++ control loop (clients/client/control_loop.h):
    in lockstep one step per tick, each with the estimate of its own sample, ending after the
    tick at the duration; stream() first hands out what a step of one's own brought, in order;
    a rig that stops under the loop raises RigLost."""
    service = serve(*RIG_ARGS)
    with mpdrig.Rig("r1", domain=service.domain, timeout=20) as rig:
        ticks = list(rig.ticks(0.5, estimates="paired"))
        assert len(ticks) == 50 and abs(ticks[-1].sensors.time_s - 0.5) < 1e-9
        assert all(t.estimate.sample_counter == t.sensors.sample_counter for t in ticks)
        assert ticks[0].dt_s == 0.0 and all(abs(t.dt_s - 0.01) < 1e-9 for t in ticks[1:])
        assert [t.index for t in ticks] == list(range(50))
        assert all(t.estimate is None for t in rig.ticks(0.6))
        rig.step(5)
        counters = [s.sample_counter for s in rig.stream(max_samples=8)]
        assert counters == list(range(counters[0], counters[0] + 8))
        assert abs(rig.status().sim_time_s - 0.68) < 1e-9  # 5 steps, then 3 of the stream
        with pytest.raises(ValueError):
            next(rig.ticks(estimates="all"))
        service.stop()
        with pytest.raises(mpdrig.RigLost):
            for _ in rig.ticks():
                pass


def test_ctrl_c_stops_the_loop_with_keyboard_interrupt(serve):
    """Ctrl-C while rig.ticks() waits in the C++ loop (without the GIL): the loop checks for it
    every 100 ms at most and Python gets its KeyboardInterrupt, as from any wait of the module."""
    service = serve("--clock", "realtime", "--rate-hz", "100", "--rig", "rt",
                    "--sensor-noise", "none")
    script = ("import sys, mpdrig\n"
              f"rig = mpdrig.Rig('rt', domain={service.domain}, timeout=20)\n"
              "try:\n"
              "    for tick in rig.ticks():\n"
              "        if tick.index == 10: print('ticking', flush=True)\n"
              "except KeyboardInterrupt:\n"
              "    print('interrupted at', tick.sensors.time_s, flush=True)\n"
              "    sys.exit(5)\n")
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "ticking"
        child.send_signal(signal.SIGINT)
        out, _ = child.communicate(timeout=20)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    assert child.returncode == 5, out
    assert out.startswith("interrupted at"), out
