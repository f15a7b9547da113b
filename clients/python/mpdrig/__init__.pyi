# Type hints for the mpdrig package (clients/python). Lab units throughout: barg, lpm, deg, m, s.
import os
from typing import Iterator, Optional, Union

import numpy as np
import numpy.typing as npt

class RigError(RuntimeError): ...
class RigLost(RigError): ...

class Sensors:
    sample_counter: int
    time_s: float
    piston_position_m: float
    choke_position_deg: float
    P1_barg: float
    P2_barg: float
    PT_barg: npt.NDArray[np.float64]  # PT1..PT10 at x = 0, 100, ..., 900 m
    BHP_barg: float  # = PT1_barg
    PT1_barg: float
    PT2_barg: float
    PT3_barg: float
    PT4_barg: float
    PT5_barg: float
    PT6_barg: float
    PT7_barg: float
    PT8_barg: float
    PT9_barg: float
    PT10_barg: float
    C1_barg: float
    C2_barg: float
    FT1_lpm: float
    FT2_lpm: float
    FT3_lpm: float
    FT4_lpm: float
    def as_dict(self) -> dict[str, float]: ...

class Estimate:
    sample_counter: int
    time_s: float
    observer_time_s: float
    BHP_est_barg: float
    piston_velocity_est_mps: float
    piston_position_est_m: float
    FT4_est_lpm: float
    disturbance_frequency_hz: float
    frequency_source: str  # "piston_sine", "tracked" or "unlocked"

class Tick:
    sensors: Sensors
    estimate: Optional[Estimate]
    dt_s: float
    index: int

class Profile:
    sample_counter: int
    time_s: float
    position_m: npt.NDArray[np.float64]
    pressure_barg: npt.NDArray[np.float64]
    pressure_est_barg: npt.NDArray[np.float64]

class Status:
    clock: str  # "realtime", "fast" or "lockstep"
    sim_time_s: float
    real_time_factor: float
    deadline_misses: int
    lost_periods: int  # real time: the sensor periods the late ticks skipped
    longest_stall_s: float  # real time: the longest stall [s of wall time]
    last_stall_sim_time_s: float  # real time: the rig time of the last stall (-1: never)
    rejected_commands: int
    last_rejection: str
    last_completed_step_request: int
    warnings: list[str]
    active_effects: list[str]
    actuator_owners: list[str]
    sensor_noise: str
    atmospheric_pressure_pa: float  # the rig's atmosphere (a playback: its log's) [Pa]

class Rig:
    def __init__(self, rig_id: str = "rig-1", domain: int = 0, *, strength: int = 0,
                 timeout: float = 10.0, dds_config: str = "",
                 security: Union[str, os.PathLike[str], None] = None) -> None: ...
    @property
    def rig_id(self) -> str: ...
    @property
    def domain(self) -> int: ...
    @property
    def strength(self) -> int: ...
    @property
    def timeout(self) -> float: ...
    @property
    def security(self) -> str: ...  # the identity directory, "" without security
    @property
    def lockstep(self) -> bool: ...
    @property
    def lost(self) -> Optional[str]: ...
    @property
    def closed(self) -> bool: ...
    def sensors(self, fresh: bool = False) -> Sensors: ...
    def next_sensors(self) -> Sensors: ...
    def pending(self) -> list[Sensors]: ...
    def stream(self, max_samples: Optional[int] = None) -> Iterator[Sensors]: ...
    def ticks(self, duration_s: Optional[float] = None, *, estimates: Optional[str] = None,
              every_sample: bool = False) -> Iterator[Tick]: ...
    def estimate(self, sample_counter: Optional[int] = None) -> Estimate: ...
    def profile(self) -> Profile: ...
    def status(self) -> Status: ...
    def rejections(self) -> tuple[int, str]: ...
    def choke(self, opening_deg: float) -> None: ...
    def pump(self, flow_lpm: float) -> None: ...
    def outlet(self, pressure_barg: float) -> None: ...
    def piston_hold(self) -> None: ...
    def piston_position(self, position_m: float) -> None: ...
    def piston_sine(self, amplitude_m: float, frequency_hz: float, mean_m: float = 0.0) -> None: ...
    def piston_sweep(self, amplitude_m: float, start_hz: float, end_hz: float,
                     duration_s: float, mean_m: float = 0.0) -> None: ...
    def step(self, steps: int = 1) -> Sensors: ...
    def close(self) -> None: ...
    def __enter__(self) -> Rig: ...
    def __exit__(self, *exc: object) -> None: ...
