"""The emulated LinMot CANopen drives (sans-I/O bus nodes), their parameter data and EDS.

    from linmot_st.emulator.models import make_drive
    drive = make_drive("E1100", 1)          # E1100Drive(node_id=1) is the same drive
    drive.power_on(0)

cia301/ holds the CiA 301 parts, linmot/ the LinMot device, motion/ the MC model; models.py the drive models.

docs/emulator.md describes the behaviour and every choice made where the sources are silent.
"""

from .codes import SdoAbort
from .linmot.command_table import CommandTable, build_entry
from .linmot.curves import Curve, CurveStore
from .linmot.drive import BOOTING, OFF, OPERATIONAL, PRE_OPERATIONAL, STOPPED, DriveTimings, E1100Drive
from .linmot.errorlog import ErrorEntry, ErrorLog
from .linmot.io import DriveIO, IoSettings
from .linmot.options import ProtocolOptions
from .linmot.profile import DriveProfile, ParamDef, ProfileError, load_profile

__all__ = [
    "E1100Drive", "DriveTimings", "ProtocolOptions", "DriveProfile", "ParamDef", "ProfileError", "load_profile",
    "Curve", "CurveStore", "CommandTable", "build_entry", "ErrorLog", "ErrorEntry", "SdoAbort",
    "DriveIO", "IoSettings",
    "OFF", "BOOTING", "PRE_OPERATIONAL", "OPERATIONAL", "STOPPED",
]
