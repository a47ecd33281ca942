"""Test helpers for the motion FBs: the motion testbench PLC (tests/st_lib/motion_testbench.st) on a simulated
bus with emulated E1100 drives that have a motor, their process data enabled.

    b = MotionBench()                      # drives 1, 2 booted, channels and FB_LmPdo enabled, TxPDO1 seen
    b.power()                              # FB_LmPower Enable until Status
    r = b.fb("MVA").run(POSITION=50.0, VELOCITY=1000.0, ACCELERATION=10000.0, DECELERATION=10000.0)
    b.drive.mc.trajectory                  # what the axis did
"""

from __future__ import annotations

from pathlib import Path

from linmot_st.emulator import DriveTimings, load_profile
from stbench import Bench

MOTION_TESTBENCH = Path(__file__).resolve().parent / "motion_testbench.st"
MM = 10_000

# a drive with a motor and position limits inside its stroke (the factory profile has no motor: setup error)
PROFILE_VALUES = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM}


class MotionBench(Bench):
    source = MOTION_TESTBENCH
    prog = "MOTION"

    def __init__(self, nodes: int = 2, *, defaults: dict | None = None, pdo: dict | None = None,
                 motion=None, **kw):
        values = dict(PROFILE_VALUES)
        values.update(defaults or {})
        drive_kwargs = {"profile": load_profile().with_defaults(values)}
        if motion is not None:
            drive_kwargs["motion"] = motion
        kw.setdefault("timings", DriveTimings.fast())
        super().__init__(nodes, drive_kwargs=drive_kwargs, **kw)
        for n in range(1, nodes + 1):
            for k, v in (pdo or {}).items():
                self[f"PDO{n}.{k}"] = v
            self[f"PDO{n}.ENABLE"] = True
        for reader in ("RSTAT", "RP", "RE"):            # the readers of axis 1 run all the time
            self[f"{reader}.ENABLE"] = True
        self.sim.run_until(lambda: all(self[f"MO{n}.TX1SEEN"] for n in range(1, nodes + 1)), max_scans=2000)

    def power(self, max_scans: int = 2000) -> None:
        self["PW.ENABLE"] = True
        self.sim.run_until(lambda: self["PW.STATUS"], max_scans=max_scans)

    def home(self) -> None:
        r = self.fb("HOME").run()
        assert r.done, r

    def ready(self) -> MotionBench:
        """Powered and homed."""
        self.power()
        self.home()
        return self

    def payloads(self, can_id: int, since_ns: int = 0) -> list[bytes]:
        return [bytes(e.frame.data) for e in self.bus.trace
                if e.frame.can_id == can_id and e.start_ns >= since_ns and e.status != "error"]
