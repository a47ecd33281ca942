"""The ErrorID numbers of the ST library, and their decoding.

This table is the single source of truth. `st_lib/types/errors.st` (the struct `T_LmErrorIds` whose members
hold these numbers as initial values, used by every FB) and the ErrorID table of `docs/st-library.md` are
generated from it
by `python -m linmot_st.protocol --write` (protocol/generate.py; `--check` exits 1 when they differ, and
`tests/protocol/test_protocol_generate.py` runs it). `describe()` turns an ErrorID (and the SDO abort
code an FB reports beside it) into text, for the commissioning report.

Scheme (ErrorID is a WORD; the high byte is the group):
  16#00xx  no error
  16#01xx  invalid input, detected before any frame is sent (which input: the low byte)
  16#02xx  the channel: not ready, busy, the FB lost its turn, mailbox full, drive rebooted
  16#03xx  the transfer: SDO timeout, SDO abort (code on the FB's AbortCode output), protocol, sequence
  16#04xx  an E1100 result code rr (byte 6 of the 60h download response, byte 4 of a curve-get answer):
           ErrorID = 16#0400 + rr, for every rr; the known codes are named below
  16#05xx  firmware compatibility (the seeds' table 5 rules)
  16#06xx  commissioning (FB_LmCommission): the dataset, the requested options, the read-back
  16#07xx  motion (st_lib/motion): the axis state, the process data, the motion command handshake; 16#014x
           invalid motion inputs

The drive's own error codes (the logged error code of the MC software, [MC] chapter 10) are a separate table:
`emulator/data/e1100_error_texts.csv` holds code, text, name and fatal flag once, and protocol/generate.py generates the
ST constants `T_LmDriveErrors` and `F_LmDriveErrorText` (st_lib/motion/drive_errors.st) and the docs table from
it (`DRIVE_ERRORS`).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

from .codes import SDO_ABORTS


@dataclass(frozen=True)
class ErrorDef:
    name: str   # member name in T_LmErrorIds (ST is case-insensitive: unique ignoring case)
    value: int
    text: str


RESULT_BASE = 0x0400

ERRORS: tuple[ErrorDef, ...] = (
    ErrorDef("NoError", 0x0000, "no error"),
    # 01xx invalid input
    ErrorDef("InvalidNodeId", 0x0101, "node ID outside 1..127"),
    ErrorDef("InvalidUpid", 0x0102, "UPID out of range (E1100: 0000h..3FFFh, the index 2000h+UPID must stay below 6000h)"),
    ErrorDef("InvalidMem", 0x0103, "memory selector not allowed for this service or drive (e.g. read of RAM+ROM, min/max/default on a B1100)"),
    ErrorDef("InvalidCurveId", 0x0104, "curve ID outside 1..100"),
    ErrorDef("TooFewSetpoints", 0x0105, "fewer than 2 setpoints"),
    ErrorDef("TooManySetpoints", 0x0106, "more setpoints than T_LmSetpoints holds (1000)"),
    ErrorDef("DataSizeMismatch", 0x0107, "data block size is not number of setpoints x 4"),
    ErrorDef("NameTooLong", 0x0108, "name too long (curve: 21 characters plus the terminating 00h, CT entry: 16)"),
    ErrorDef("InvalidChar", 0x0109, "name or text holds a character outside printable ASCII (20h..7Eh)"),
    ErrorDef("InfoDataOffset", 0x010A, "curve info block: data offset is not 70"),
    ErrorDef("InfoObjectType", 0x010B, "curve info block: object type is not 0003h (position/time) or 0103h (cam)"),
    ErrorDef("InfoTypeSize", 0x010C, "curve info block: data type size is not 4"),
    ErrorDef("InfoCurveId", 0x010D, "curve info block: its curve ID differs from the CurveId input"),
    ErrorDef("InvalidCtEntry", 0x010E, "command-table entry number outside 0..255"),
    ErrorDef("CtVersion", 0x010F, "command-table block: version ID is not A701h"),
    ErrorDef("CtLink", 0x0110, "command-table block: linked entry is neither FFFFh nor 0..255"),
    ErrorDef("InvalidLayer", 0x0111, "firmware layer outside 1..4"),
    ErrorDef("InvalidStringletCount", 0x0112, "stringlet count outside 1..32"),
    ErrorDef("TextTooLong", 0x0113, "text longer than 4 x the stringlet count"),
    ErrorDef("NotSupported", 0x0114, "service or command not supported by this drive type (B1100: curves and curve motions, command table, defaults, UPID lists)"),
    ErrorDef("NothingSelected", 0x0115, "flash save with neither Curves nor CommandTable selected"),
    ErrorDef("InvalidUpidRange", 0x0116, "UPID list: start UPID above end UPID"),
    ErrorDef("InvalidSdoCommand", 0x0117, "raw SDO: index below 1000h or above 5FFFh"),
    # 02xx channel
    ErrorDef("NotReady", 0x0201, "channel not ready: FB_LmChannel not called for this axis, or not yet enabled"),
    ErrorDef("ChannelDisabled", 0x0202, "the channel's Enable input is FALSE"),
    ErrorDef("NodeLost", 0x0203, "the drive's heartbeat stopped (channel HeartbeatTimeout)"),
    ErrorDef("ChannelBusy", 0x0204, "waited longer than the channel's QueueTimeout for its turn"),
    ErrorDef("Evicted", 0x0205, "the FB was not called while it held the channel and lost its turn"),
    ErrorDef("TxFull", 0x0206, "the mailbox Tx array was full: frame not queued"),
    ErrorDef("DriveRebooted", 0x0207, "the drive sent a boot-up message during the service"),
    ErrorDef("NodeIdInUse", 0x0208, "another channel of the same mailbox owns this node ID: nothing is sent for it"),
    # 03xx transfer
    ErrorDef("SdoTimeout", 0x0301, "no SDO response within the timeout"),
    ErrorDef("SdoAbort", 0x0302, "the drive answered with an SDO abort (code on the AbortCode output)"),
    ErrorDef("SdoProtocol", 0x0303, "unexpected SDO response (not an expedited answer of the requested kind)"),
    ErrorDef("Sequence", 0x0304, "the drive's result code disagrees with the transfer length (finished early, or not at the end)"),
    ErrorDef("BootTimeout", 0x0305, "reset: no boot-up message within BootTimeout"),
    ErrorDef("FlashTimeout", 0x0306, "flash save: still busy after FlashTimeout"),
    ErrorDef("UploadBlockSize", 0x0307, "the drive reported an info block size other than 70, or a CT block size other than 64"),
    ErrorDef("UploadTooBig", 0x0308, "the curve on the drive has more setpoints than T_LmSetpoints holds, or a data size not a multiple of 4"),
    ErrorDef("UploadInconsistent", 0x0309, "uploaded curve: the info block's setpoints x 4 differ from the data size"),
    ErrorDef("ListFull", 0x030A, "UPID list longer than T_LmUpidList holds (the list holds the first 2048)"),
    ErrorDef("NotOperational", 0x030B, "after its boot-up the drive did not report NMT Operational within BootTimeout (FailActual = the last NMT state it reported, 00h none)"),
    ErrorDef("WriteNotConfirmed", 0x030C, "a write to an object whose earlier exchange timed out was answered 'written' but reads back another value: the answer may have been the late one of that exchange (CiA 301 has no transaction number); the drive holds what was read"),
    # 04xx E1100 result codes (16#0400 + rr)
    ErrorDef("ResultBase", RESULT_BASE, "E1100 result code rr: ErrorID = 16#0400 + rr (the named ones follow)"),
    ErrorDef("ResultNotFinished", RESULT_BASE + 0x04, "result 04h: block not finished where the end was expected / flash busy"),
    ErrorDef("ResultUpidError", RESULT_BASE + 0xC0, "result C0h: UPID error"),
    ErrorDef("ResultTypeError", RESULT_BASE + 0xC1, "result C1h: parameter type error"),
    ErrorDef("ResultRangeError", RESULT_BASE + 0xC2, "result C2h: range error"),
    ErrorDef("ResultUsageError", RESULT_BASE + 0xC3, "result C3h: address usage error"),
    ErrorDef("ResultListNotStarted", RESULT_BASE + 0xC5, "result C5h: get next UPID without start"),
    ErrorDef("ResultListEnd", RESULT_BASE + 0xC6, "result C6h: end of UPID list"),
    ErrorDef("ResultBlockFinished", RESULT_BASE + 0xD0, "result D0h: block already finished"),
    ErrorDef("ResultBlockSize", RESULT_BASE + 0xD1, "result D1h: invalid block size"),
    ErrorDef("ResultObjectState", RESULT_BASE + 0xD4,
             "result D4h: the curve or command-table entry is in the wrong state for the request: the curve "
             "already exists or is being written (add), the curve or entry is not present (get), invalid entry"),
    ErrorDef("ResultMcNotStopped", RESULT_BASE + 0xD7, "result D7h: MC software not stopped"),
    # 05xx compatibility
    ErrorDef("TreeIdMismatch", 0x0501, "firmware layer: tree ID of the source differs from the drive's"),
    ErrorDef("MainVersionMismatch", 0x0502, "firmware layer: main version of the source differs from the drive's"),
    ErrorDef("SubVersionNewer", 0x0503, "firmware layer: sub version of the source is newer than the drive's"),
    # 06xx commissioning
    ErrorDef("DatasetInvalid", 0x0601, "commissioning dataset malformed: magic word, format version, counts or record order wrong (FailStep = the word index)"),
    ErrorDef("ResetNeedsFlash", 0x0602, "reset requested without the flash save while the dataset holds curves or command-table entries (the reset would lose them)"),
    ErrorDef("VerifyMismatch", 0x0603, "read-back differs from the dataset (FailItem, FailStep, FailExpected, FailActual say where)"),
    ErrorDef("NoSuchUpid", 0x0604, "pre-flight: the drive has no parameter with this UPID (FailItem); nothing was written"),
    ErrorDef("NotWritable", 0x0605, "pre-flight: the drive's parameter cannot be written (its address usage has no ROM write); nothing was written"),
    ErrorDef("AboveMax", 0x0606, "pre-flight: the dataset's value (FailActual) is above the drive's maximum (FailExpected); nothing was written"),
    ErrorDef("BelowMin", 0x0607, "pre-flight: the dataset's value (FailActual) is below the drive's minimum (FailExpected); nothing was written"),
    ErrorDef("CurveMemory", 0x0608, "pre-flight: the curves need more bytes (FailActual) than the drive's curve memory (FailExpected, the CurveMemory input); nothing was written"),
    # 0140..014F invalid motion input (before any frame is sent)
    ErrorDef("InvalidVelocity", 0x0140, "motion: velocity zero, negative, or beyond what the command can carry"),
    ErrorDef("InvalidAcceleration", 0x0141, "motion: acceleration zero, negative, or beyond what the command can carry"),
    ErrorDef("InvalidDeceleration", 0x0142, "motion: deceleration zero, negative, or beyond what the command can carry"),
    ErrorDef("PositionRange", 0x0143, "motion: position or distance beyond what the chosen command carries (16-bit: the 16-bit interface scaling; 32-bit: +-214.7 m)"),
    ErrorDef("ScaleRange", 0x0144, "motion: curve time scale outside 0..200 % or amplitude scale outside -2000..2000 %"),
    ErrorDef("InvalidCurveTime", 0x0145, "motion: curve time zero, negative or above 21474 s"),
    ErrorDef("InvalidMode", 0x0146, "motion: the Mode or Command input names no known variant"),
    ErrorDef("InvalidBusBudget", 0x0147, "process-data budget: Axes below 1, or a Bitrate that is not a multiple of 1000"),
    ErrorDef("UnknownCommand", 0x014C, "FB_LmMotionCommand: the command ID is none the encoder knows (the catalogue, F_LmMotionEncode)"),
    ErrorDef("JogDirection", 0x014D, "FB_LmJog: JogForward and JogBackward both TRUE"),
    ErrorDef("MotionEnded", 0x014E, "FB_LmMoveVelocity / FB_LmCamIn: the drive ended the infinite motion or the cam operation without a newer command (a position limit)"),
    ErrorDef("InvalidIoNumber", 0x014F, "digital I/O: the input or output number is not one of the connector's (X4 inputs 0..9 = X4.3..X4.12, X4 outputs 0..8 = X4.3..X4.11, X6 0..15)"),
    # 07xx motion (st_lib/motion): the axis, the process data, the command handshake
    ErrorDef("AxisNotEnabled", 0x0701, "the axis is not in Operation Enabled (state 8): power it with FB_LmPower first"),
    ErrorDef("AxisNotHomed", 0x0702, "the move needs the axis homed (FB_LmHome, or a master homing)"),
    ErrorDef("McNotRunning", 0x0703, "the drive's MC software is stopped (status word and state var 0): no motion"),
    ErrorDef("NoProcessData", 0x0704, "no valid TxPDO from the drive: none since the enable or the drive's reset, or the last older than FB_LmPdo's PdoTimeout"),
    ErrorDef("CommandTimeout", 0x0705, "the drive did not take the motion command (no count echo) within CommandTimeout, resends included"),
    ErrorDef("DriveError", 0x0706, "the drive is in error (state 3, 4 or 14): its logged error code is on the DriveError output (T_LmDriveErrors)"),
    ErrorDef("StopActive", 0x0707, "FB_LmStop holds the axis: no motion command until its Execute falls (MC_Stop)"),
    ErrorDef("AxisEnabled", 0x0708, "the axis is enabled (state 5..17): this service stops the MC software; switch the axis off (FB_LmPower) first"),
    ErrorDef("PowerTimeout", 0x0709, "FB_LmPower: the drive did not reach Operation Enabled within Timeout"),
    ErrorDef("HomeTimeout", 0x070A, "FB_LmHome: homing did not finish within Timeout"),
    ErrorDef("ResetTimeout", 0x070B, "FB_LmReset: the drive did not leave the error state within Timeout"),
    ErrorDef("FatalError", 0x070C, "the drive's error is fatal (status word bit 12): only a reset or a power cycle clears it"),
    ErrorDef("AxisBusy", 0x070D, "the axis is homing, in another special state or stopping (abort, freeze): it takes no motion command now"),
    ErrorDef("CommandNotMapped", 0x070E, "the command needs more parameter bytes than the RxPDOs carry (FB_LmPdo Rx3Bytes; the drive's RxPDO3 mapping 2041h)"),
    ErrorDef("PowerLost", 0x070F, "the axis left Operation Enabled while the FB was busy"),
)

BY_VALUE: dict[int, ErrorDef] = {e.value: e for e in ERRORS}
BY_NAME: dict[str, ErrorDef] = {e.name: e for e in ERRORS}


@dataclass(frozen=True)
class DriveErrorDef:
    name: str       # member name in T_LmDriveErrors
    code: int       # the logged error code
    text: str       # the drive's error text (8 stringlets)
    fatal: bool


def _load_drive_errors() -> tuple[DriveErrorDef, ...]:
    path = Path(__file__).resolve().parents[1] / "emulator" / "data" / "e1100_error_texts.csv"
    with open(path, newline="", encoding="latin-1") as f:
        rows = csv.DictReader(line for line in f if not line.startswith("#"))
        return tuple(DriveErrorDef(r["name"], int(r["code"], 16), r["text"], r["fatal"] == "1") for r in rows)


DRIVE_ERRORS: tuple[DriveErrorDef, ...] = _load_drive_errors()
DRIVE_ERRORS_BY_CODE: dict[int, DriveErrorDef] = {d.code: d for d in DRIVE_ERRORS}


def drive_error_text(code: int) -> str:
    """The drive's text for a logged error code ('' when the table has none)."""
    d = DRIVE_ERRORS_BY_CODE.get(code)
    return d.text if d else ""

def describe(error_id: int, abort_code: int = 0) -> str:
    """Text for an ErrorID of the library (and the SDO abort code reported with ErrorID SdoAbort)."""
    e = BY_VALUE.get(error_id)
    if e is not None and e.name != "ResultBase":
        text = e.text
    elif RESULT_BASE <= error_id <= RESULT_BASE + 0xFF:
        text = f"E1100 result code {error_id - RESULT_BASE:02X}h"
    else:
        return f"unknown ErrorID 16#{error_id:04X}"
    if error_id == BY_NAME["SdoAbort"].value:
        text += f": {abort_code:08X}h {SDO_ABORTS.get(abort_code, 'unknown abort code')}"
    return f"16#{error_id:04X} {text}"


def name_of(error_id: int) -> str:
    """Member name in T_LmErrorIds, or ResultXXh for an unnamed E1100 result code."""
    e = BY_VALUE.get(error_id)
    if e is not None:
        return e.name
    if RESULT_BASE <= error_id <= RESULT_BASE + 0xFF:
        return f"Result{error_id - RESULT_BASE:02X}h"
    return f"16#{error_id:04X}"
