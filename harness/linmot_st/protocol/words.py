"""The words of the MC software's interface (seed 004 chapter 3, [MC] chapter 3 and 10): main states, control
word, status word and warn word bits, and the error codes the motion model raises.

Only numbers live here (the catalogue: the PLC library and the emulated drive share them); the behaviour is in
the drive's MC model (emulator/linmot/motion/).
"""

from __future__ import annotations

from .errors import DRIVE_ERRORS

# ---- main states (state var high byte) ------------------------------------------------------------------
NOT_READY_TO_SWITCH_ON = 0
SWITCH_ON_DISABLED = 1
READY_TO_SWITCH_ON = 2
SETUP_ERROR = 3
ERROR = 4
HW_TESTS = 5
READY_TO_OPERATE = 6
OPERATION_ENABLED = 8
HOMING = 9
CLEARANCE_CHECK = 10
GOING_TO_INITIAL_POSITION = 11
ABORTING = 12
FREEZING = 13
ERROR_QUICK_STOP = 14
GOING_TO_POSITION = 15
JOGGING_PLUS = 16
JOGGING_MINUS = 17
SPECIAL_MODE = 20                 # B1100 only (seed 004 3.20): current command from the analog input

STATE_NAMES = {
    0: "Not Ready To Switch On", 1: "Switch On Disabled", 2: "Ready To Switch On", 3: "Setup Error", 4: "Error",
    5: "HW Tests", 6: "Ready To Operate", 8: "Operation Enabled", 9: "Homing", 10: "Clearance Check",
    11: "Going To Initial Position", 12: "Aborting", 13: "Freezing", 14: "Error Behaviour Quick Stop",
    15: "Going To Position", 16: "Jogging +", 17: "Jogging -",
}

# states whose sub state 0Fh says "finished" (the "special motion" states of status word bit 9)
SPECIAL_STATES = (HOMING, CLEARANCE_CHECK, GOING_TO_INITIAL_POSITION, GOING_TO_POSITION, JOGGING_PLUS, JOGGING_MINUS)
SUB_FINISHED = 0x0F

# ---- control word --------------------------------------------------------------------------------------
CW_SWITCH_ON = 1 << 0
CW_VOLTAGE_ENABLE = 1 << 1
CW_QUICK_STOP_N = 1 << 2          # 0 = quick stop (OFF3)
CW_ENABLE_OPERATION = 1 << 3
CW_ABORT_N = 1 << 4               # 0 = abort
CW_FREEZE_N = 1 << 5              # 0 = freeze
CW_GO_TO_POSITION = 1 << 6
CW_ERROR_ACK = 1 << 7             # rising edge
CW_JOG_PLUS = 1 << 8
CW_JOG_MINUS = 1 << 9
CW_SPECIAL_MODE = 1 << 10         # B1100 only: refused on the E1100
CW_HOME = 1 << 11
CW_CLEARANCE_CHECK = 1 << 12
CW_GO_TO_INITIAL_POSITION = 1 << 13   # rising edge
CW_PHASE_SEARCH = 1 << 15         # state 19: out of scope, refused

# ---- status word ---------------------------------------------------------------------------------------
SW_OPERATION_ENABLED = 1 << 0
SW_SWITCH_ON_ACTIVE = 1 << 1
SW_ENABLE_OPERATION = 1 << 2
SW_ERROR = 1 << 3
SW_VOLTAGE_ENABLE = 1 << 4
SW_QUICK_STOP_N = 1 << 5
SW_SWITCH_ON_LOCKED = 1 << 6
SW_WARNING = 1 << 7
SW_EVENT_HANDLER = 1 << 8
SW_SPECIAL_MOTION = 1 << 9
SW_IN_TARGET = 1 << 10
SW_HOMED = 1 << 11
SW_FATAL = 1 << 12
SW_MOTION_ACTIVE = 1 << 13
SW_RANGE_1 = 1 << 14
SW_RANGE_2 = 1 << 15

# state var low byte in state 8
SV_EVENT_HANDLER = 1 << 4
SV_MOTION_ACTIVE = 1 << 5
SV_IN_TARGET = 1 << 6
SV_HOMED = 1 << 7

# ---- warn word -----------------------------------------------------------------------------------------
WARN_POS_LAG_ALWAYS = 1 << 4
WARN_POS_LAG_STANDING = 1 << 5
WARN_MOTOR_NOT_HOMED = 1 << 7

# ---- error codes ([MC] chapter 10; the ones the model raises) -----------------------------------------
ERR_MIN_POS_UNDERSHOT = 0x0007
ERR_MAX_POS_OVERSHOT = 0x0008
ERR_POS_LAG_ALWAYS = 0x000B
ERR_POS_LAG_STANDING = 0x000C
ERR_CURVE_NOT_DEFINED = 0x0062
ERR_NO_MOTOR_DEFINED = 0x0064
ERR_NOT_HOMED = 0x0080
ERR_UNKNOWN_MOTION_CMD = 0x0081
ERR_PVT_BUFFER_OVERFLOW = 0x0082      # streams ([MC] 10): setpoints too fast
ERR_PVT_BUFFER_UNDERFLOW = 0x0083     # too slow, or the stream stopped without 03Fxh
ERR_PVT_MASTER_TOO_FAST = 0x0084      # the first two setpoints closer than the mode's shortest period
ERR_PVT_MASTER_TOO_SLOW = 0x0085      # ... farther apart than its longest
ERR_MOTION_CMD_WRONG_STATE = 0x0086
ERR_CURVE_AMP_SCALE = 0x0089
ERR_CMD_TAB_ENTRY_NOT_DEFINED = 0x008A

# the codes [MC] marks "Fatal Err" (status word bit 12: no acknowledge, only a reset clears them): the
# drive's error table (data/e1100_error_texts.csv) says which
FATAL_ERRORS = frozenset(d.code for d in DRIVE_ERRORS if d.fatal)
