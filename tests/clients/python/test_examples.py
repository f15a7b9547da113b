"""The recorder writes a rig log (rig-log-format.md) that `mpdrig compare` reads; the live plot
at least imports headless (its window is not tested)."""

from __future__ import annotations

import io
import json
import os
import subprocess

import mpdrig
from test_bhp_controller import load_example


def test_recorder_writes_a_rig_log_the_tools_read(serve, tmp_path):
    record = load_example("record")
    service = serve("--clock", "lockstep", "--rate-hz", "100", "--pump-lpm", "5",
                    "--choke-deg", "31", "--sensor-noise", "none", "--heave-amp-m", "0.05",
                    "--heave-hz", "0.5", "--rig", "r1")
    out = io.StringIO()
    with mpdrig.Rig("r1", domain=service.domain, timeout=20) as rig:
        atmosphere = rig.status().atmospheric_pressure_pa
        rows = record.write_log(out, rig.stream(max_samples=600), "test", atmosphere)
    assert rows == 600
    assert atmosphere == 101325.0  # the service's default atmosphere, as its status says
    lines = out.getvalue().splitlines()
    assert lines[0] == "# rig-log: 1"
    assert lines[2] == "# atmospheric_pressure_pa: 101325"
    header = lines[3].split(",")
    assert header == record.COLUMNS and len(lines) == 4 + 600
    times = [float(line.split(",")[0]) for line in lines[4:]]
    assert all(b > a for a, b in zip(times, times[1:]))
    # The project's own reader takes it: `mpdrig compare` refuses a malformed log with its line.
    path = tmp_path / "run.csv"
    path.write_text(out.getvalue())
    compared = subprocess.run([os.environ["MPDRIG_EXE"], "compare", str(path), "--json", "m.json"],
                              capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert compared.returncode == 0, compared.stderr
    # Replayed through the same model, the recording must come back: at the heave frequency the
    # model's PT1 and C2 amplitudes match the recorded ones (measured: ratio 0.998, bias 0.002
    # bar; the replay only differentiates the recorded piston position). A column in the wrong
    # unit or order would be off by orders of magnitude or by bars.
    metrics = json.loads((tmp_path / "m.json").read_text())
    for channel in ("PT1", "C2", "FT1"):
        fundamental = metrics["channels"][channel]["bands"][0]
        assert abs(fundamental["magnitude_ratio"] - 1.0) < 0.05, (channel, fundamental)
        assert abs(metrics["channels"][channel]["bias"]) < 0.05, channel


def test_live_plot_imports_headless(monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    plot = load_example("live_plot")
    assert callable(plot.main)
