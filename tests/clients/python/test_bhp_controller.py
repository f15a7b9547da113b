"""The Python example controller (clients/python/examples/bhp_controller.py) holds the bottom-hole
pressure like the C++ one: the scenario and bounds of tests/clients/bhp_controller_test.cc."""

from __future__ import annotations

import importlib.util
import os
import sys
import time

import mpdrig

EXAMPLES = os.path.join(os.environ.get("MPDRIG_SOURCE_DIR", ""), "clients", "python", "examples")


def load_example(name: str):
    spec = importlib.util.spec_from_file_location(name, os.path.join(EXAMPLES, name + ".py"))
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def test_python_controller_attenuates_the_heave_induced_bhp_oscillation(serve):
    example = load_example("bhp_controller")
    # 0.1 m heave at 0.2 Hz near the pipe's quarter-wave resonance (c/4l = 0.24 Hz), 5 L/min
    # through a 31 deg choke: about 0.38 bar of BHP amplitude with the choke fixed. At the lab's
    # sensor noise (serve's default), as the C++ test. 65 s: 20 s to settle and learn the set
    # point, about 20 s to converge, the last 20 s measured.
    service = serve("--clock", "lockstep", "--rate-hz", "100", "--heave-amp-m", "0.1",
                    "--heave-hz", "0.2", "--pump-lpm", "5", "--choke-deg", "31",
                    "--noise-seed", "4", "--rig", "fixed", "--rig", "controlled")
    started = time.monotonic()
    with mpdrig.Rig("fixed", domain=service.domain, timeout=30) as rig:
        fixed = example.run(rig, 65.0, 20.0, open_loop=True)
    with mpdrig.Rig("controlled", domain=service.domain, strength=10, timeout=30) as rig:
        controlled = example.run(rig, 65.0, 20.0, use_estimate=True)
    ratio = fixed.periodic_rms_bar / controlled.periodic_rms_bar
    print(f"PT1 periodic RMS: fixed choke {fixed.periodic_rms_bar:.4f} bar, controlled "
          f"(observer estimate, Python) {controlled.periodic_rms_bar:.4f} bar, ratio {ratio:.1f}; "
          f"means {fixed.mean_barg:.4f} / {controlled.mean_barg:.4f} barg; "
          f"{time.monotonic() - started:.1f} s of wall time")
    # The last 20 s at 100 Hz, every sample seen (the window's first edge may fall either side
    # of a sample time in floating point: one more or less).
    assert abs(fixed.n - 2000) <= 1 and abs(controlled.n - 2000) <= 1
    assert fixed.periodic_rms_bar > 0.2, "the heave must move the BHP by tenths of a bar"
    # Measured 20.7x (21.8x over 80 s); the C++ controller reaches 18-23x over 65 s at the lab's
    # noise. 5x, as its test asks, leaves room for tuning, not for a controller that merely does no
    # harm (PI alone: 0.97x).
    assert ratio > 5.0
    # It holds the mean too, as the C++ test asks: within 0.02 bar.
    assert abs(controlled.mean_barg - fixed.mean_barg) < 0.02
