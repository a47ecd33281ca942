"""The motion half of the emulated E1100: the MC software's state machine, motion command interpreter,
setpoint generation, the axis that follows it, and the trajectory record (the PDOs: emulator/cia301/pdo.py)
(docs/emulator.md section 13).

    from linmot_st.emulator import E1100Drive
    from linmot_st.emulator.linmot.motion import MotionSettings
    drive = E1100Drive(1, motion=MotionSettings(bandwidth_hz=40))
    drive.mc.trajectory.samples        # what the axis did
"""

from .axis import Axis
from .control import MotionControl
from .setpoints import CurvePlan, StopPlan, VaPlan
from .settings import MotionSettings
from .trajectory import Sample, Trajectory

__all__ = ["Axis", "CurvePlan", "MotionControl", "MotionSettings", "Sample", "StopPlan", "Trajectory", "VaPlan"]
