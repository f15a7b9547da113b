#!/usr/bin/env python3
"""Record what a rig publishes as a rig log (rig-log-format.md), like rig_echo, in Python.

    python3 record.py --rig rig-1 --domain 0 --samples 6000 --out run.csv
    (on a lockstep rig it steps the rig once per sample)

The file goes straight into `mpdrig compare`. A lost rig ends the recording (exit 3); the file
keeps the whole rows written before.
"""

from __future__ import annotations

import argparse
import sys
from typing import Iterable, TextIO

import mpdrig

COLUMNS = ["time_s", "piston_position_m", "choke_position_deg", "FT2_lpm", "C1_barg",
           "P1_barg", "P2_barg"] + [f"PT{i}_barg" for i in range(1, 11)] + [
           "C2_barg", "FT1_lpm", "FT3_lpm", "FT4_lpm"]


def write_log(out: TextIO, samples: Iterable[mpdrig.Sensors], source: str,
              atmospheric_pressure_pa: float = 101325.0) -> int:
    """Writes the rig-log header and one row per sample with increasing time; returns the rows.

    atmospheric_pressure_pa: the rig's atmosphere (Rig.status().atmospheric_pressure_pa), which
    its *_barg channels are gauge against."""
    out.write(f"# rig-log: 1\n# source: {source}\n"
              f"# atmospheric_pressure_pa: {atmospheric_pressure_pa:.12g}\n")
    out.write(",".join(COLUMNS) + "\n")
    rows = 0
    last_time = -float("inf")
    try:
        for s in samples:
            if not s.time_s > last_time:  # a rig log's time is strictly increasing
                continue
            row = s.as_dict()
            out.write(",".join(repr(row[c]) for c in COLUMNS) + "\n")
            last_time = s.time_s
            rows += 1
    except KeyboardInterrupt:  # Ctrl-C ends the recording, on a whole row
        pass
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rig", default="rig-1")
    parser.add_argument("--domain", type=int, default=0)
    parser.add_argument("--samples", type=int, default=0, help="stop after this many (0: Ctrl-C)")
    parser.add_argument("--out", default="-", help="rig log to write ('-': stdout)")
    parser.add_argument("--timeout", type=float, default=10.0,
                        help="seconds without a sample before the rig counts as lost")
    args = parser.parse_args()
    out = sys.stdout if args.out == "-" else open(args.out, "w", encoding="utf-8")
    rows = 0
    try:
        with mpdrig.Rig(args.rig, domain=args.domain, timeout=args.timeout) as rig:
            source = f"record.py, rig {args.rig}, DDS domain {args.domain}"
            atmosphere = rig.status().atmospheric_pressure_pa
            rows = write_log(out, rig.stream(args.samples or None), source, atmosphere)
    except mpdrig.RigLost as lost:
        print(f"record.py: {lost}; the recording ends there", file=sys.stderr)
        return 3
    except (mpdrig.RigError, TimeoutError) as error:
        print(f"record.py: {error}", file=sys.stderr)
        return 1
    finally:
        out.flush()
        if out is not sys.stdout:
            out.close()
    print(f"record.py: {rows} samples of {args.rig} recorded", file=sys.stderr)
    return 0 if rows > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
